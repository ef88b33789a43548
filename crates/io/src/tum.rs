//! TUM trajectories (Sturm et al., IROS 2012): one pose per line, `t x y z qx qy qz qw`
//! (time in seconds, position in metres, unit quaternion `world_from_sensor`), `#` comments.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use raypath_geometry::{Pose2, Pose3};

use crate::Result;
use crate::error::{Error, Location};
use crate::source::{LineReader, finite_fields};

/// One stamped pose of a TUM trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TumPose {
    /// Time stamp in seconds, as the file states it.
    pub time_s: f64,
    /// The pose (`world_from_sensor`); the quaternion is normalised.
    pub pose: Pose3,
}

/// Reads a TUM trajectory (plain or compressed).
pub fn read_tum(path: &Path) -> Result<Vec<TumPose>> {
    tum_from(LineReader::open(path)?)
}

/// Parses a TUM trajectory from `reader`; `name` is used in errors.
pub fn parse_tum(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<TumPose>> {
    tum_from(LineReader::new(reader, name))
}

const FIELDS: [&str; 8] = ["t", "x", "y", "z", "qx", "qy", "qz", "qw"];

fn tum_from(mut lines: LineReader) -> Result<Vec<TumPose>> {
    let mut poses = Vec::new();
    while let Some(line) = lines.next_line()?.map(|l| l.trim().to_owned()) {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let [t, x, y, z, qx, qy, qz, qw] =
            finite_fields(&lines, &line, FIELDS, "t x y z qx qy qz qw")?;
        let q = Quaternion::new(qw, qx, qy, qz);
        if q.norm() < 1e-9 {
            return Err(lines.error("zero quaternion"));
        }
        poses.push(TumPose {
            time_s: t,
            pose: Pose3::from_parts(Vector3::new(x, y, z), UnitQuaternion::from_quaternion(q)),
        });
    }
    Ok(poses)
}

/// Planar poses with their time stamps as TUM lines (`t x y z qx qy qz qw`: z = 0 and a yaw
/// quaternion; `t x y` with six decimals, the quaternion with nine). The one TUM writer of
/// the workspace: `raypath slam`, `scan-match` and `localize` write through it.
pub fn planar_tum_lines(stamped: impl IntoIterator<Item = (f64, Pose2)>) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    for (t, p) in stamped {
        let half = p.theta() / 2.0;
        let _ = writeln!(
            out,
            "{t:.6} {:.6} {:.6} 0 0 0 {:.9} {:.9}",
            p.x(),
            p.y(),
            half.sin(),
            half.cos()
        );
    }
    out
}

/// Writes [`planar_tum_lines`] to `path`, after `# comment` when one is given.
pub fn write_planar_tum(
    path: &Path,
    comment: Option<&str>,
    stamped: impl IntoIterator<Item = (f64, Pose2)>,
) -> Result<()> {
    let mut text = comment.map_or_else(String::new, |c| format!("# {c}\n"));
    text.push_str(&planar_tum_lines(stamped));
    std::fs::write(path, text).map_err(|e| Error::io(path, Location::File, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<TumPose>> {
        parse_tum(std::io::Cursor::new(text.to_owned()), "test.tum")
    }

    #[test]
    fn reads_poses_and_skips_comments() {
        let poses =
            parse("# t x y z qx qy qz qw\n1.5 1 2 3 0 0 0.7071068 0.7071068\n\n2 0 0 0 0 0 0 2\n")
                .expect("valid file");
        assert_eq!(poses.len(), 2);
        assert_eq!(poses[0].time_s, 1.5);
        let p = poses[0].pose.to_planar();
        assert!((p.x() - 1.0).abs() < 1e-12 && (p.y() - 2.0).abs() < 1e-12);
        assert!((p.theta() - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
        // A non-unit quaternion is normalised.
        assert!(poses[1].pose.to_planar().theta().abs() < 1e-12);
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        for text in [
            "1 2 3\n",
            "1 2 3 4 5 6 7 8 9\n",
            "0 0 0 0 0 0 0 0\n",
            "0 nan 0 0 0 0 0 1\n",
            "# ok\n0 0 0 0 0 0 0 x\n",
        ] {
            let e = parse(text).expect_err(text).to_string();
            assert!(e.contains("test.tum:"), "{e}");
        }
    }
}
