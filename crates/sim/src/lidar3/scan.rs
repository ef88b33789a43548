//! Casting a lidar's beams into a scene: [`Lidar3::scan`] and its result, [`SimScan`].

use nalgebra::{Point3, Unit, Vector3};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use raypath_geometry::{BeamDirections, PointCloud, Pose3, RangeImage};

use super::Lidar3;
use crate::error::{Result, SimError};
use crate::rng::{self, SimRng};
use crate::scene3::{Scene3, SurfaceId};

/// Random-stream domain of the beams of a scan (offset by the scan index).
const DOMAIN_SCAN: u64 = 0x4c49_4441_5233_0001;
/// Random-stream domain of [`SimScan::with_range_noise`] (offset by the stream index).
const DOMAIN_EXTRA_NOISE: u64 = 0x4c49_4441_5233_0002;

/// One simulated scan, organized `rows × cols` like the lidar.
#[derive(Clone, Debug, PartialEq)]
pub struct SimScan {
    /// The points in the sensor frame (`height = rows`, `width = cols`, NaN for no-returns)
    /// with `intensity` (in `[0, 1]`, 0 for no-returns) and `label` (the label of the surface
    /// hit, 0 for no-returns).
    pub cloud: PointCloud,
    /// The surface each beam hit (also set for returns lost to dropout or to the detection
    /// threshold, `None` when nothing was hit within the range limits).
    pub surfaces: Vec<Option<SurfaceId>>,
    /// The noise-free range along the beam as cast (with its angular noise), metres; NaN when
    /// nothing was hit within the range limits. Returns lost to dropout keep their range: this
    /// is the ideal image of the scene.
    pub true_ranges_m: Vec<f32>,
    /// Nominal elevation of each row, radians.
    pub elevations_rad: Vec<f64>,
    /// Nominal azimuth of each column, radians.
    pub azimuths_rad: Vec<f64>,
}

/// What one beam produced.
#[derive(Clone, Copy)]
struct Pixel {
    point: Point3<f32>,
    intensity: f32,
    label: u32,
    surface: Option<SurfaceId>,
    true_range_m: f32,
}

const NAN_POINT: Point3<f32> = Point3::new(f32::NAN, f32::NAN, f32::NAN);

const EMPTY: Pixel = Pixel {
    point: NAN_POINT,
    intensity: 0.0,
    label: 0,
    surface: None,
    true_range_m: f32::NAN,
};

impl Lidar3 {
    /// Scans `scene` from `world_from_sensor`: one beam per pixel, rows in parallel. The
    /// result depends only on the lidar, the scene, the pose, `seed` and `scan_index`
    /// (different scan indices draw different noise), not on the number of threads.
    pub fn scan(
        &self,
        scene: &Scene3,
        world_from_sensor: &Pose3,
        seed: u64,
        scan_index: u64,
    ) -> Result<SimScan> {
        self.scan_moving(
            scene,
            world_from_sensor,
            &Vector3::zeros(),
            seed,
            scan_index,
        )
    }

    /// [`scan`](Self::scan) from a sensor moving by `sweep_translation_m` (sensor frame,
    /// metres) over the revolution at constant velocity, as a de-skewed sweep: `world_from_sensor`
    /// is the pose when the sensor faces forward (azimuth 0, the middle column of a rotating
    /// lidar, which spins clockwise from the back); the beam of a column fired a fraction `τ`
    /// of a revolution later starts `τ · sweep_translation_m` from there, and its point is
    /// reported in the sensor frame at that pose (moving origin + measured range along the
    /// nominal direction), so free space seen by the beam starts where the sensor was — the
    /// timing of KITTI's de-skewed HDL-64E sweeps. Rotation during the sweep is ignored.
    pub fn scan_moving(
        &self,
        scene: &Scene3,
        world_from_sensor: &Pose3,
        sweep_translation_m: &Vector3<f64>,
        seed: u64,
        scan_index: u64,
    ) -> Result<SimScan> {
        self.validate()?;
        if !sweep_translation_m.iter().all(|v| v.is_finite()) {
            return Err(SimError::InvalidParameter {
                name: "sweep_translation_m",
                reason: "not finite".into(),
            });
        }
        if !world_from_sensor.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "world_from_sensor",
                reason: "the pose is not finite".into(),
            });
        }
        let cols = self.cols();
        let row_trig: Vec<(f64, f64)> = self.elevations_rad.iter().map(|e| e.sin_cos()).collect();
        let col_trig: Vec<(f64, f64)> = self.azimuths_rad.iter().map(|a| a.sin_cos()).collect();
        let rotation = world_from_sensor.rotation();
        let origin = Point3::from(world_from_sensor.translation());
        let domain = DOMAIN_SCAN.wrapping_add(scan_index);

        let mut pixels = vec![EMPTY; self.num_rays()];
        pixels
            .par_chunks_mut(cols)
            .enumerate()
            .for_each(|(row, out)| {
                let mut rng = rng::stream(seed, domain, row as u64);
                let (el, (sin_el, cos_el)) = (self.elevations_rad[row], row_trig[row]);
                for ((pixel, &az), &(sin_az, cos_az)) in
                    out.iter_mut().zip(&self.azimuths_rad).zip(&col_trig)
                {
                    let nominal = Vector3::new(cos_el * cos_az, cos_el * sin_az, sin_el);
                    let cast_dir = if self.angular_noise_sigma_rad > 0.0 {
                        let d_el: f64 = rng.sample(StandardNormal);
                        let d_az: f64 = rng.sample(StandardNormal);
                        let sigma = self.angular_noise_sigma_rad;
                        let (se, ce) = (el + sigma * d_el).sin_cos();
                        let (sa, ca) = (az + sigma * d_az).sin_cos();
                        Vector3::new(ce * ca, ce * sa, se)
                    } else {
                        nominal
                    };
                    // Fraction of a clockwise revolution after facing forward, in [−½, ½).
                    let turned = -az / std::f64::consts::TAU;
                    let tau = turned - (turned + 0.5).floor();
                    let offset = sweep_translation_m * tau;
                    let start = origin + rotation * offset;
                    *pixel = self.beam(scene, &start, &(rotation * cast_dir), &nominal, &mut rng);
                    pixel.point += offset.cast::<f32>();
                }
            });

        let n = pixels.len();
        let mut points = Vec::with_capacity(n);
        let mut intensity = Vec::with_capacity(n);
        let mut label = Vec::with_capacity(n);
        let mut surfaces = Vec::with_capacity(n);
        let mut true_ranges_m = Vec::with_capacity(n);
        for p in &pixels {
            points.push(p.point);
            intensity.push(p.intensity);
            label.push(p.label);
            surfaces.push(p.surface);
            true_ranges_m.push(p.true_range_m);
        }
        Ok(SimScan {
            cloud: PointCloud {
                points,
                intensity: Some(intensity),
                label: Some(label),
                rgb: None,
                width: cols,
                height: self.rows(),
            },
            surfaces,
            true_ranges_m,
            elevations_rad: self.elevations_rad.clone(),
            azimuths_rad: self.azimuths_rad.clone(),
        })
    }

    /// One beam: cast along `cast_dir_world` (unit), report along `nominal` (sensor frame).
    fn beam(
        &self,
        scene: &Scene3,
        origin: &Point3<f64>,
        cast_dir_world: &Vector3<f64>,
        nominal: &Vector3<f64>,
        rng: &mut SimRng,
    ) -> Pixel {
        let direction = Unit::new_unchecked(*cast_dir_world);
        let Some(hit) = scene.cast(origin, &direction, self.max_range_m) else {
            return EMPTY;
        };
        if hit.range_m < self.min_range_m {
            return EMPTY;
        }
        let surface = scene.surface(hit.surface);
        let mut pixel = Pixel {
            surface: Some(hit.surface),
            true_range_m: hit.range_m as f32,
            ..EMPTY
        };
        let measured = if self.range_noise_sigma_m > 0.0 {
            let z: f64 = rng.sample(StandardNormal);
            (hit.range_m + self.range_noise_sigma_m * z).max(0.0)
        } else {
            hit.range_m
        };
        if self.dropout_probability > 0.0 && rng.random::<f64>() < self.dropout_probability {
            return pixel;
        }
        let reflectivity = surface.map_or(0.0, |s| f64::from(s.reflectivity));
        let cos_incidence = hit.normal.dot(cast_dir_world).abs();
        let model = &self.intensity;
        let expected = model.expected(reflectivity, hit.range_m, cos_incidence);
        if expected < model.detection_threshold {
            return pixel;
        }
        let intensity = if model.noise_sigma > 0.0 {
            model.measured(expected, rng.sample(StandardNormal))
        } else {
            expected
        };
        pixel.point = Point3::from((nominal * measured).cast::<f32>());
        pixel.intensity = intensity as f32;
        pixel.label = surface.map_or(0, |s| s.label);
        pixel
    }
}

impl SimScan {
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.cloud.height
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cloud.width
    }

    /// Measured ranges in metres, row by row; NaN for no-returns.
    pub fn ranges_m(&self) -> Vec<f32> {
        self.cloud
            .points
            .iter()
            .map(|p| {
                if p.x.is_nan() {
                    f32::NAN
                } else {
                    p.coords.norm()
                }
            })
            .collect()
    }

    fn directions(&self) -> BeamDirections {
        BeamDirections::Spherical {
            elevations_rad: self.elevations_rad.clone(),
            azimuths_rad: self.azimuths_rad.clone(),
        }
    }

    /// The measured range image (nominal directions) with intensity and label channels.
    pub fn range_image(&self) -> Result<RangeImage> {
        let image = RangeImage::new(self.rows(), self.cols(), self.directions(), self.ranges_m())
            .and_then(|i| match &self.cloud.intensity {
                Some(v) => i.with_intensity(v.clone()),
                None => Ok(i),
            })
            .and_then(|i| match &self.cloud.label {
                Some(v) => i.with_label(v.clone()),
                None => Ok(i),
            });
        image.map_err(|e| SimError::InvalidScene {
            reason: format!("range image: {e}"),
        })
    }

    /// The ideal range image: noise-free ranges, no dropout, nominal directions.
    pub fn ideal_range_image(&self) -> Result<RangeImage> {
        RangeImage::new(
            self.rows(),
            self.cols(),
            self.directions(),
            self.true_ranges_m.clone(),
        )
        .map_err(|e| SimError::InvalidScene {
            reason: format!("ideal range image: {e}"),
        })
    }

    /// The cloud with extra Gaussian range noise of `sigma_m` added to every return, each
    /// point moved along its ray (no-returns stay NaN; ranges are clamped at 0). Row `i`
    /// draws from the stream `(seed, stream_index, i)`: the same arguments give the same
    /// cloud. Used to derive several noise levels from one noise-free scan.
    pub fn with_range_noise(
        &self,
        sigma_m: f64,
        seed: u64,
        stream_index: u64,
    ) -> Result<PointCloud> {
        if !(sigma_m.is_finite() && sigma_m >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "sigma_m",
                reason: format!("{sigma_m} (expected a finite value ≥ 0)"),
            });
        }
        let mut cloud = self.cloud.clone();
        if sigma_m == 0.0 {
            return Ok(cloud);
        }
        let domain = DOMAIN_EXTRA_NOISE.wrapping_add(stream_index);
        let cols = self.cols().max(1);
        cloud
            .points
            .par_chunks_mut(cols)
            .enumerate()
            .for_each(|(row, points)| {
                let mut rng = rng::stream(seed, domain, row as u64);
                for p in points.iter_mut().filter(|p| !p.x.is_nan()) {
                    let z: f64 = rng.sample(StandardNormal);
                    let v = p.coords.cast::<f64>();
                    let range = v.norm();
                    if range > 0.0 {
                        let scale = (range + sigma_m * z).max(0.0) / range;
                        *p = Point3::from((v * scale).cast::<f32>());
                    }
                }
            });
        Ok(cloud)
    }
}
