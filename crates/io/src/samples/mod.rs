//! Small valid files of every format this crate reads, for tests, fuzzing and examples.
//!
//! Each function returns [`Sample`]s: the bytes and the file name a reader should be given
//! (errors name it). Samples are written with the crate's own writers where it has them
//! (CARMEN, KITTI, NCLT, OctoMap, PCD, rosbag2, pole CSV) and by hand otherwise (Ouster
//! captures and metadata, SegComp rasters, TUM, x y z, CSV); the `.Z` streams are reference
//! files made by ncompress 4.2.4.6. They are small on purpose: a mutation of a small input
//! reaches every field, which is what `cargo xtask fuzz` and the readers' property tests
//! need. Everything is deterministic: the same call gives the same bytes.
//!
//! ```
//! use raypath_io::samples;
//! use raypath_io::pcd::{self, ReadOptions};
//!
//! for sample in samples::pcd()? {
//!     let read = pcd::read_pcd_bytes(&sample.bytes, &sample.name, &ReadOptions::default())?;
//!     assert!(!read.cloud.points.is_empty());
//! }
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod binary;
mod named;
pub(crate) mod ouster;
mod pcap;
mod rosbag;
mod text;

pub use binary::{
    LZW_STREAMS, kitti_labels, kitti_velodyne, lzw, nclt_hits, nclt_sync, octomap_bt,
    octomap_graph, pcd, segcomp_gt_ang, segcomp_gt_seg, segcomp_range,
};
pub use named::named_files;
pub use ouster::{Capture, OusterSample, ouster_capture, ouster_sensors};
pub use pcap::{classic_pcap, ip_frames, pcapng, udp_datagram, udp_frames};
pub use rosbag::{rosbag_bags, rosbag_cdr};
pub use text::{
    CARMEN_LOG, carmen, kitti_calib, kitti_poses, kitti_times, nclt_covariance, nclt_pose_csv,
    point_csv, poles_csv, relations, rosbag_metadata, tum, xyz,
};

/// One sample input and the file name it is read under.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sample {
    /// The file name to give the reader (format detection goes by it).
    pub name: String,
    /// The file's bytes.
    pub bytes: Vec<u8>,
}

impl Sample {
    /// A sample named `name`.
    pub fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> Self {
        Self {
            name: name.into(),
            bytes: bytes.into(),
        }
    }
}
