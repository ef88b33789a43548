//! CARMEN logs: 2-D laser scans, odometry and parameters, one message per text line.
//!
//! The format is the log format of the CARMEN robot navigation toolkit (Montemerlo, Roy and
//! Thrun, IROS 2003; <http://carmen.sourceforge.net>), in which the Radish repository (Howard
//! and Roy, 2003) and the SLAM benchmark collection distribute their indoor logs. Files are
//! plain text, `.gz` or `.bz2` (recognized by their first bytes). The messages read here:
//!
//! ```text
//! FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
//! RLASER (the same, for the rear laser)
//! ROBOTLASER1 laser_type start_angle fov angular_res max_range accuracy remission_mode
//!             n r_1 … r_n n_rem rem_1 … rem_n_rem laser_x laser_y laser_theta
//!             robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis
//!             ipc_timestamp ipc_hostname logger_timestamp
//! ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
//! PARAM name value [ipc_timestamp] ipc_hostname logger_timestamp
//! # comment
//! ```
//!
//! Other messages (`NEFF`, `TRUEPOS`, `SYNC`, `RAWLASER1`, …) become [`Record::Other`].
//!
//! [`CarmenWriter`] writes the same messages (deterministic number formatting, see
//! [`NumberFormat`]); a log written and read back gives the records that were written.
//!
//! **Units and frames.** Metres, radians and seconds; poses are `(x, y, θ)` with θ
//! counter-clockwise (REP-103: x forward, y left). The laser pose `x y theta` is
//! [`LaserMessage::world_from_laser`]; in the `*-corrected` logs it is the SLAM-corrected
//! reference pose, in raw logs the odometry. Both timestamps are kept as `f64` seconds: the
//! IPC timestamp (usually UNIX time) and the logger timestamp (usually time since the logger
//! started; the corrected logs print it with fewer digits).
//!
//! **Beam angles.** `ROBOTLASER1` lines state the first angle and the increment. `FLASER`
//! and `RLASER` lines do not: beam 0 points to the robot's right (−90°) and the fan spans
//! the field of view (π unless `PARAM laser_front_laser_fov` says otherwise) by the
//! [`FanConvention`] of [`CarmenConfig`]. The default, [`FanConvention::Auto`], puts beam `i`
//! at −90° + i·180°/(n − n mod 2): 1° steps for 180 and 181 beams, 0.5° for 360 and 361, the
//! last beam at +89°/+89.5° for even counts and +90° for odd ones. It was chosen
//! empirically: rendered with the reference poses, it gives the sharpest maps of all ten
//! corrected Radish logs (fewest occupied 5 cm cells; `cargo xtask eval carmen-angles`,
//! report in `docs/results/carmen-angles.md`).
//! A `PARAM laser_front_laser_resolution` line (degrees) sets the increment.
//!
//! **No-returns.** Readings at or above [`raypath_geometry::Scan2::max_range_m`] are
//! no-returns. The reader infers each log's no-return code (a repeated maximum reading) in
//! a first pass or a look-ahead, see [`no_return`]; [`NoReturnRange::Fixed`] overrides it.
//!
//! ```no_run
//! use raypath_io::carmen::{CarmenConfig, CarmenReader, NoReturnRange, Record};
//! let path = std::path::Path::new("datasets/carmen/raw/intel.clf.bz2");
//! let config = CarmenConfig { no_return: NoReturnRange::Fixed(81.83), ..Default::default() };
//! let scans = CarmenReader::open_with(path, config)?
//!     .filter(|r| matches!(r, Ok(Record::Laser(_))))
//!     .count();
//! assert_eq!(scans, 13631);
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod config;
pub mod no_return;
mod params;
mod parse;
mod reader;
mod record;
mod summarize;
mod write;

pub use config::{CarmenConfig, FanConvention, NoReturnRange};
pub use no_return::{NoReturnEstimate, NoReturnHistogram};
pub use reader::CarmenReader;
pub use record::{LaserKind, LaserMessage, OdometryMessage, Record, RobotLaserInfo, Velocities};
pub use summarize::summarize;
pub use write::{CarmenWriter, Decimals, NumberFormat};
