//! `cargo xtask eval segcomp`: PPE, the PEAC-style baseline and MSAC under the SegComp
//! protocol of Schaefer (2020, § 11.5, Table 11.1) — each method's parameters grid-searched
//! on the training images for the best mean fraction f of correctly segmented planes, then
//! scored on the test images by the Hoover et al. (1996) evaluator at 80 % overlap (f, k,
//! RMSE, α, n_o, n_u, n_m, n_s).
//!
//! Two data sets, two tables: the **real** SegComp Perceptron images when installed under
//! `$RAYPATH_DATA/segcomp/` (`perceptron/{train,test}/` as in `datasets/manifest.json`, or
//! flat), and always the **simulated** SegComp-like stand-in of `raypath_sim::segcomp`
//! (generated in memory from a fixed seed), every row of which says it is simulated. The
//! thesis' rows stay beside them as the reference.
//!
//! In stages (`--shard i/n`, `merge`): one unit per data set — `real` (the real images; its
//! result records when they are not installed) and `standin` (the simulated images) — each
//! the whole protocol on its set, since the test images are scored with the cell the grid
//! search on the same set's training images chose; [`page`] draws the report from their
//! results.

mod files;
mod page;
mod protocol;
mod standin;

use anyhow::{Result, bail};
use raypath_sim::segcomp::Split;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::EvalContext;
use super::stages::Staged;
use protocol::Outcome;

const NAME: &str = "segcomp";

/// The stand-in's seed (the workspace's default seed of generated sets).
const SEED: u64 = raypath_sim::datasets::DEFAULT_SEED;

/// The evaluation in stages (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report: page::report,
};

/// The units: the real set, the stand-in.
const REAL: &str = "real";
const STANDIN: &str = "standin";

fn units(_: &EvalContext) -> Result<Vec<String>> {
    Ok(vec![REAL.to_owned(), STANDIN.to_owned()])
}

fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    Ok(match unit {
        REAL => serde_json::to_value(measure_real(ctx)?)?,
        STANDIN => serde_json::to_value(standin::measure(ctx)?)?,
        _ => bail!("{NAME} has no unit {unit:?}"),
    })
}

/// The real set's result.
#[derive(Serialize, Deserialize)]
struct RealUnit {
    /// `None` when no `perc.test.N` lies under `$RAYPATH_DATA/segcomp` (not installed).
    measured: Option<RealMeasured>,
}

/// The protocol on the real images.
#[derive(Serialize, Deserialize)]
struct RealMeasured {
    outcome: Outcome,
    /// Training images found (none: the untuned parameters were used).
    train_images: usize,
}

/// Runs the protocol on the real SegComp images when installed (the unit `real`).
fn measure_real(ctx: &EvalContext) -> Result<RealUnit> {
    let root = ctx.data("segcomp");
    let mut test_files = files::find(&root, Split::Test);
    let mut train_files = files::find(&root, Split::Train);
    if test_files.is_empty() {
        eprintln!(
            "segcomp: no perc.test.N under {} — running the simulated stand-in only",
            root.display()
        );
        return Ok(RealUnit { measured: None });
    }
    if ctx.quick {
        train_files.truncate(2);
        test_files.truncate(3);
    }
    let train = train_files
        .iter()
        .map(files::load)
        .collect::<Result<Vec<_>>>()?;
    let outcome = protocol::run(ctx, "real", &train, test_files.len(), |i| {
        files::load(&test_files[i])
    })?;
    Ok(RealUnit {
        measured: Some(RealMeasured {
            outcome,
            train_images: train.len(),
        }),
    })
}
