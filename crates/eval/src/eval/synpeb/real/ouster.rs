//! The Ouster table: real organized OS-1/OS-2 frames, no labels.

use anyhow::Result;
use serde_json::{Map, Value};

use super::data;
use super::score::Pooled;
use super::{NOT_LIKE_FOR_LIKE, key, pct, run_methods};
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// The Ouster captures: (pcap, metadata, name, key).
const CAPTURES: [(&str, &str, &str, &str); 2] = [
    (
        "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
        "ouster/OS-1-128_v2.3.0_1024x10.json",
        "OS-1-128, 1024 × 128",
        "os1",
    ),
    (
        "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap",
        "ouster/OS-2-128-U1_v2.3.0_1024x10.json",
        "OS-2-128, 1024 × 128",
        "os2",
    ),
];

/// The Ouster table (markdown) and its JSON.
pub fn run(ctx: &EvalContext) -> Result<(String, Value)> {
    let mut table = Table::new([
        "data (real)",
        "method",
        "frames",
        "planes/frame",
        "returns on planes [%]",
        "RMSE [mm]",
        "time/frame [s]",
        "like for like with Table 11.1",
    ]);
    let mut results = Map::new();
    for (pcap, meta, name, tag) in CAPTURES {
        let (pcap, meta) = (ctx.data(pcap), ctx.data(meta));
        if !(pcap.is_file() && meta.is_file()) {
            let absent = format!("absent: {}", pcap.display());
            table.row([name, "–", "0", &absent, "–", "–", "–", NOT_LIKE_FOR_LIKE]);
            continue;
        }
        let frames = data::ouster_frames(&pcap, &meta, name)?;
        for (method, scores) in run_methods(ctx, &frames, tag)? {
            let p = Pooled::of(&scores);
            table.row([
                name.to_owned(),
                method.name().to_owned(),
                p.frames.to_string(),
                fmt_num(p.planes, 1),
                pct(p.on_plane),
                fmt_num(p.rmse_mm, 1),
                fmt_num(p.median_secs, 2),
                NOT_LIKE_FOR_LIKE.into(),
            ]);
            results.insert(format!("{}_{tag}", key(&method)), p.json());
        }
    }
    Ok((table.to_markdown()?, Value::Object(results)))
}
