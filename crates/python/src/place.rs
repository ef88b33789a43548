//! `raypath.place_recognition.ScanContext`: a Scan Context database of 3-D scans.

use pyo3::prelude::*;
use raypath_geometry::PointCloud;
use raypath_place_recognition::{
    Frame, PlaceRecognizer, ScanContext as Database, ScanContextConfig,
};

use crate::arrays::points;
use crate::errors::{input_error, value_error};

/// Scan Context place recognition (Kim & Kim 2018): add 3-D scans (sensor frame) one by one,
/// query a scan against those added. Scores are `1 − d` of the yaw-invariant column distance
/// (higher = more similar).
///
/// `num_sectors`: sectors over 360°. `max_range`: farther points are ignored, metres.
/// `num_candidates`: ring-key nearest neighbours scored fully (None = every scan).
#[pyclass(module = "raypath.place_recognition", name = "ScanContext")]
pub struct ScanContext {
    db: Database,
}

fn cloud(obj: &Bound<'_, PyAny>) -> PyResult<PointCloud> {
    let (rows, _) = points(obj, "cloud", &[3, 4])?;
    Ok(PointCloud::from_points(
        rows.iter()
            .map(|p| nalgebra::Point3::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect(),
    ))
}

#[pymethods]
impl ScanContext {
    #[new]
    #[pyo3(signature = (num_sectors = 60, max_range = 80.0, num_candidates = Some(10)))]
    fn new(num_sectors: usize, max_range: f64, num_candidates: Option<usize>) -> PyResult<Self> {
        let config = ScanContextConfig {
            num_sectors,
            max_range,
            num_candidates,
            ..ScanContextConfig::default()
        };
        let db = Database::new(config).map_err(|e| value_error("ScanContext", e))?;
        Ok(Self { db })
    }

    /// Adds a scan, `(N, 3)` or `(N, 4)` float32/float64 in the sensor frame. Returns its
    /// index.
    fn add(&mut self, py: Python<'_>, cloud: &Bound<'_, PyAny>) -> PyResult<usize> {
        let c = self::cloud(cloud)?;
        let db = &mut self.db;
        py.allow_threads(|| {
            let d = db.describe(&Frame::Cloud(&c))?;
            db.insert(d);
            Ok(db.len() - 1)
        })
        .map_err(|e: raypath_place_recognition::PlaceError| input_error(e))
    }

    /// Scores a scan against every scan added: a list of `(index, score)`, best first, at
    /// most `k` of them (all candidates when `k` is None).
    #[pyo3(signature = (cloud, k = None))]
    fn query(
        &mut self,
        py: Python<'_>,
        cloud: &Bound<'_, PyAny>,
        k: Option<usize>,
    ) -> PyResult<Vec<(usize, f64)>> {
        let c = self::cloud(cloud)?;
        let db = &mut self.db;
        let mut found = py
            .allow_threads(|| {
                let d = db.describe(&Frame::Cloud(&c))?;
                Ok(db.query(&d, db.len()))
            })
            .map_err(|e: raypath_place_recognition::PlaceError| input_error(e))?;
        found.sort_by(|a, b| b.score.total_cmp(&a.score).then(a.frame.cmp(&b.frame)));
        if let Some(k) = k {
            found.truncate(k);
        }
        Ok(found.into_iter().map(|c| (c.frame, c.score)).collect())
    }

    fn __len__(&self) -> usize {
        self.db.len()
    }

    fn __repr__(&self) -> String {
        format!("ScanContext({} scans)", self.db.len())
    }
}
