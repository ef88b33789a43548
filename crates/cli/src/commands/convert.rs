//! `raypath convert`: between CARMEN logs, the KITTI layout, PCD files and rosbag2 bags, and
//! from Ouster captures, so the public benchmark logs become bags and back
//! (`raypath_io::convert`).

use std::path::PathBuf;

use raypath_io::convert::{ConvertOptions, Target, convert};
use raypath_io::rosbag::{BagCompression, BagWriteOptions};

use super::Failure;
use super::source_args::SourceArgs;

/// Chunk compression of a written bag.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Compression {
    /// zstd (rosbag2's default for compressed MCAP).
    #[default]
    Zstd,
    /// LZ4 frames.
    Lz4,
    /// No compression.
    None,
}

/// `--to`: the output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum To {
    /// A CARMEN log (plain text).
    Carmen,
    /// A KITTI sequence directory.
    Kitti,
    /// A PCD file (one sweep) or a directory of PCD files (one per sweep).
    Pcd,
    /// A rosbag2 bag: an .mcap file, or a bag directory with metadata.yaml.
    Rosbag2,
}

impl From<To> for Target {
    fn from(to: To) -> Self {
        match to {
            To::Carmen => Target::Carmen,
            To::Kitti => Target::Kitti,
            To::Pcd => Target::Pcd,
            To::Rosbag2 => Target::Rosbag2,
        }
    }
}

/// Arguments of `raypath convert`.
#[derive(clap::Args)]
pub struct Args {
    /// The input: a CARMEN log, a KITTI sequence, an NCLT session, an Ouster capture (.pcap
    /// with its metadata JSON beside it), a PCD file, or a rosbag2 bag (a directory with
    /// metadata.yaml, or an .mcap file).
    pub input: PathBuf,
    /// The output: `.mcap` (a rosbag2 file), `.log`/`.clf` (CARMEN), `.pcd`, or a directory
    /// (KITTI layout for 3-D input, a rosbag2 bag directory for planar input); `--to` decides
    /// when the name does not.
    pub output: PathBuf,
    /// The output format.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub to: Option<To>,
    /// Chunk compression of a written bag.
    #[arg(long, value_enum, default_value_t = Compression::Zstd)]
    pub compression: Compression,
    #[command(flatten)]
    pub source: SourceArgs,
}

/// Runs `raypath convert`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let options = ConvertOptions {
        target: args.to.map(Target::from),
        planar: args.source.planar_options(),
        sweeps: args.source.sweep_options(),
        bag: BagWriteOptions {
            compression: match args.compression {
                Compression::Zstd => BagCompression::Zstd,
                Compression::Lz4 => BagCompression::Lz4,
                Compression::None => BagCompression::None,
            },
            ..BagWriteOptions::default()
        },
    };
    let report = convert(&args.input, &args.output, &options).map_err(Failure::input)?;
    if super::console::json() {
        println!(
            "{}",
            serde_json::to_string(&report).map_err(Failure::input)?
        );
    } else {
        println!(
            "{} ({}) → {} ({}): {} frames, {} with reference poses",
            args.input.display(),
            report.from,
            report.output.display(),
            serde_json::to_value(report.to)
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default(),
            report.frames,
            report.reference_poses
        );
    }
    Ok(())
}
