//! The real organized scans: KITTI frames projected ring by ring with their SemanticKITTI
//! classes per pixel, and Ouster frames as the sensor delivers them.

use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::{Point3, Vector3};
use raypath_geometry::{PointCloud, RingProjection};
use raypath_io::kitti::{KittiSequence, PointLabel};
use raypath_io::ouster::{OusterReader, SensorInfo};

/// Lasers of the Velodyne HDL-64E (rows of a KITTI range image).
pub const KITTI_RINGS: usize = 64;
/// Firings per revolution of the HDL-64E at 10 Hz (columns of a KITTI range image; the
/// workspace's sensor model `raypath_sim::lidar3::HDL64E_FIRINGS_10HZ`).
pub const KITTI_COLUMNS: usize = raypath_sim::lidar3::HDL64E_FIRINGS_10HZ;

/// One organized real scan.
pub struct Frame {
    /// `sequence/frame` (KITTI) or `capture #k` (Ouster).
    pub name: String,
    /// The organized cloud (rays from the origin; NaN for no-returns).
    pub cloud: PointCloud,
    /// SemanticKITTI class per pixel (0 for empty pixels), when labelled.
    pub classes: Option<Vec<u16>>,
    /// Points (returns) in the source before projection.
    pub source_points: usize,
}

/// KITTI frame `frame` of `seq` as a 64 × 2083 range image (row = laser ring, recovered from
/// the storage order; column = azimuth), its labels carried per pixel.
pub fn kitti_frame(seq: &KittiSequence, frame: u64) -> Result<Frame> {
    let name = format!("{}/{frame:06}", seq.name.as_deref().unwrap_or("?"));
    let mut cloud = seq
        .scan(frame)
        .with_context(|| format!("KITTI {name}: no velodyne file"))?
        .with_context(|| format!("reading KITTI {name}"))?;
    let labels = seq
        .labels(frame)
        .with_context(|| format!("reading the labels of KITTI {name}"))?;
    let labelled = labels.is_some();
    cloud.label = labels.map(|l| l.into_iter().map(PointLabel::raw).collect());
    let source_points = cloud.len();
    let projection = RingProjection::new(KITTI_RINGS, KITTI_COLUMNS)?;
    let image = projection
        .project(&cloud, &Point3::origin())
        .with_context(|| format!("projecting KITTI {name}"))?;
    let organized = image.to_point_cloud(&Point3::origin());
    let classes = labelled.then(|| {
        organized
            .label
            .iter()
            .flatten()
            .map(|&raw| PointLabel::from_raw(raw).class)
            .collect()
    });
    Ok(Frame {
        name,
        cloud: organized,
        classes,
        source_points,
    })
}

/// The first-return frames of an Ouster capture as organized `H × W` clouds. Points are
/// given from the lidar origin (the sensor frame's axes, the sensor-from-lidar translation
/// removed) so every ray starts within the beam-origin radius (≈ 1.5 cm) of the origin, as
/// the extractors assume.
pub fn ouster_frames(pcap: &Path, json: &Path, label: &str) -> Result<Vec<Frame>> {
    let info = SensorInfo::read(json).with_context(|| format!("reading {}", json.display()))?;
    let t = info.lidar_to_sensor_transform;
    let lidar_origin = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]) / 1000.0;
    let mut frames = Vec::new();
    for (k, frame) in OusterReader::open(pcap, &info)
        .with_context(|| format!("opening {}", pcap.display()))?
        .enumerate()
    {
        let frame = frame.with_context(|| format!("decoding {}", pcap.display()))?;
        let mut cloud = frame
            .to_point_cloud(&info)
            .with_context(|| format!("points of {}", pcap.display()))?;
        let shift = lidar_origin.cast::<f32>();
        for p in &mut cloud.points {
            *p -= shift;
        }
        frames.push(Frame {
            name: format!("{label} #{k}"),
            source_points: frame.valid_returns(),
            cloud,
            classes: None,
        });
    }
    Ok(frames)
}
