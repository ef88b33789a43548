//! Map export: ROS `map_server` PGM + YAML, PNG pictures, and the binary map format.

mod binary;
mod report;
mod ros_map;

pub use binary::{MapFile, MapKind, StoredStats};
pub use report::{Extent, MapFiles, MapReport, write_map_files};
pub use ros_map::{
    MapPicture, RosMapOptions, UNKNOWN_PIXEL, map_image, picture_value, picture_values, write_png,
    write_ros_map,
};
