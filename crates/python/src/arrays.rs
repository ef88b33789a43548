//! NumPy arrays in and out: dtype and shape checks that name the argument and the shape
//! expected.

use numpy::ndarray::{Array2, Array3};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::value_error;

/// A float array read from Python: its values as `f64` in row-major order, its shape, and
/// whether it came as `float32` (so callers can keep single precision exact).
pub struct Floats {
    /// Row-major values.
    pub values: Vec<f64>,
    /// The shape.
    pub shape: Vec<usize>,
    /// True for a `float32` input.
    pub single: bool,
}

/// Reads `obj` (a NumPy array, or anything `numpy.asarray` turns into one) as float32 or
/// float64; any other dtype is a `ValueError` naming `name` and `expected`.
pub fn floats(obj: &Bound<'_, PyAny>, name: &str, expected: &str) -> PyResult<Floats> {
    floats_as(obj, name, expected, false)
}

/// [`floats`]; with `coerce`, integer and other numeric arrays are converted to float64
/// first (for small arguments such as an origin or a pose, where `[0, 0, 0]` is natural).
pub fn floats_as(
    obj: &Bound<'_, PyAny>,
    name: &str,
    expected: &str,
    coerce: bool,
) -> PyResult<Floats> {
    let py = obj.py();
    let array = if obj.downcast::<numpy::PyUntypedArray>().is_ok() {
        obj.clone()
    } else {
        py.import("numpy")?
            .call_method1("asarray", (obj,))
            .map_err(|e| {
                value_error(
                    name,
                    format!(
                        "expected {expected}, got an object NumPy cannot read as an array ({e})"
                    ),
                )
            })?
    };
    let array = if coerce
        && array.downcast::<PyArrayDyn<f64>>().is_err()
        && array.downcast::<PyArrayDyn<f32>>().is_err()
    {
        let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
        if matches!(kind.as_str(), "i" | "u" | "b" | "f") {
            array.call_method1("astype", ("float64",))?
        } else {
            array
        }
    } else {
        array
    };
    if let Ok(a) = array.downcast::<PyArrayDyn<f64>>() {
        let ro = a.readonly();
        let view = ro.as_array();
        return Ok(Floats {
            shape: view.shape().to_vec(),
            values: view.iter().copied().collect(),
            single: false,
        });
    }
    if let Ok(a) = array.downcast::<PyArrayDyn<f32>>() {
        let ro = a.readonly();
        let view = ro.as_array();
        return Ok(Floats {
            shape: view.shape().to_vec(),
            values: view.iter().map(|&v| f64::from(v)).collect(),
            single: true,
        });
    }
    let described = match array.downcast::<numpy::PyUntypedArray>() {
        Ok(a) => format!("a {} array of shape {:?}", a.dtype(), a.shape()),
        Err(_) => format!("a {}", array.get_type().name()?),
    };
    Err(value_error(
        name,
        format!("expected {expected} (float32 or float64), got {described}"),
    ))
}

/// An `(N, 3)` (or `(N, k)` with `k` in `columns`) float array: the rows' first three values.
pub fn points(
    obj: &Bound<'_, PyAny>,
    name: &str,
    columns: &[usize],
) -> PyResult<(Vec<[f64; 3]>, bool)> {
    let cols: Vec<String> = columns.iter().map(usize::to_string).collect();
    let expected = format!("an array of shape (N, {})", cols.join(" or "));
    let f = floats(obj, name, &expected)?;
    let [n, k] = f.shape[..] else {
        return Err(value_error(
            name,
            format!("expected {expected}, got shape {:?}", f.shape),
        ));
    };
    if !columns.contains(&k) {
        return Err(value_error(
            name,
            format!("expected {expected}, got shape ({n}, {k})"),
        ));
    }
    if n == 0 {
        return Err(value_error(
            name,
            format!("expected {expected} with N ≥ 1, got no points"),
        ));
    }
    let mut out = Vec::with_capacity(n);
    for (i, row) in f.values.chunks_exact(k).enumerate() {
        if !row[..3].iter().all(|v| v.is_finite()) {
            return Err(value_error(
                name,
                format!("row {i} is not finite ({}, {}, {})", row[0], row[1], row[2]),
            ));
        }
        out.push([row[0], row[1], row[2]]);
    }
    Ok((out, f.single))
}

/// A 1-D float array of finite values (at least `min_len` of them).
pub fn vector(
    obj: &Bound<'_, PyAny>,
    name: &str,
    min_len: usize,
    coerce: bool,
) -> PyResult<Vec<f64>> {
    let expected = "an array of shape (N,)";
    let f = floats_as(obj, name, expected, coerce)?;
    if f.shape.len() != 1 {
        return Err(value_error(
            name,
            format!("expected {expected}, got shape {:?}", f.shape),
        ));
    }
    if f.values.len() < min_len {
        return Err(value_error(
            name,
            format!("expected at least {min_len} values, got {}", f.values.len()),
        ));
    }
    Ok(f.values)
}

/// A `(4, 4)` rigid transform as a pose; `None` when `obj` is `None`.
pub fn pose3(
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<Option<raypath_geometry::Pose3>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let expected = "a rigid transform of shape (4, 4)";
    let f = floats_as(obj, name, expected, true)?;
    if f.shape != [4, 4] {
        return Err(value_error(
            name,
            format!("expected {expected}, got shape {:?}", f.shape),
        ));
    }
    if !f.values.iter().all(|v| v.is_finite()) {
        return Err(value_error(name, "not finite"));
    }
    let m = nalgebra::Matrix3x4::from_row_slice(&f.values[..12]);
    raypath_geometry::Pose3::try_from_matrix3x4(&m)
        .map(Some)
        .ok_or_else(|| value_error(name, "the upper-left 3 × 3 block is not a rotation"))
}

/// One planar pose as a `(3,)` array `x, y, theta`.
pub fn pose_vector(py: Python<'_>, pose: raypath_geometry::Pose2) -> Bound<'_, PyArray1<f64>> {
    vec1(py, vec![pose.x(), pose.y(), pose.theta()])
}

/// `(N, 3)` array of poses `x, y, theta`.
pub fn poses2<'py>(
    py: Python<'py>,
    poses: impl ExactSizeIterator<Item = raypath_geometry::Pose2>,
) -> Bound<'py, PyArray2<f64>> {
    let n = poses.len();
    let flat: Vec<f64> = poses.flat_map(|p| [p.x(), p.y(), p.theta()]).collect();
    matrix(py, flat, n, 3)
}

/// `(N, 4, 4)` array of rigid transforms.
pub fn poses3<'py>(
    py: Python<'py>,
    poses: &[raypath_geometry::Pose3],
) -> Bound<'py, PyArray3<f64>> {
    let flat: Vec<f64> = poses.iter().flat_map(homogeneous).collect();
    match Array3::from_shape_vec((poses.len(), 4, 4), flat) {
        Ok(a) => a.into_pyarray(py),
        // The length is 16 per pose by construction.
        Err(_) => Array3::zeros((0, 4, 4)).into_pyarray(py),
    }
}

/// One rigid transform as a `(4, 4)` array.
pub fn pose3_matrix<'py>(
    py: Python<'py>,
    pose: &raypath_geometry::Pose3,
) -> Bound<'py, PyArray2<f64>> {
    matrix(py, homogeneous(pose).to_vec(), 4, 4)
}

/// The 16 values of a rigid transform's homogeneous matrix, row-major.
fn homogeneous(pose: &raypath_geometry::Pose3) -> [f64; 16] {
    let m = pose.to_matrix3x4();
    let mut out = [0.0; 16];
    for r in 0..3 {
        for c in 0..4 {
            out[4 * r + c] = m[(r, c)];
        }
    }
    out[15] = 1.0;
    out
}

/// A row-major `(rows, cols)` array from `flat` (`rows · cols` values).
pub fn matrix<T: numpy::Element + Default + Clone>(
    py: Python<'_>,
    flat: Vec<T>,
    rows: usize,
    cols: usize,
) -> Bound<'_, PyArray2<T>> {
    match Array2::from_shape_vec((rows, cols), flat) {
        Ok(a) => a.into_pyarray(py),
        // Callers pass rows · cols values by construction.
        Err(_) => Array2::from_elem((0, cols), T::default()).into_pyarray(py),
    }
}

/// A 1-D array.
pub fn vec1<T: numpy::Element>(py: Python<'_>, v: Vec<T>) -> Bound<'_, PyArray1<T>> {
    v.into_pyarray(py)
}

/// An `(N, 3)` or `(N, 4)` float array as a point cloud in single precision (a fourth
/// column, such as KITTI's reflectance, is ignored), as the readers of `raypath_io` give it.
pub fn point_cloud(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<raypath_geometry::PointCloud> {
    let (rows, _) = points(obj, name, &[3, 4])?;
    Ok(raypath_geometry::PointCloud::from_points(
        rows.iter()
            .map(|p| nalgebra::Point3::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect(),
    ))
}

/// A planar pose `(x, y, theta)` from a `(3,)` array of finite values.
pub fn pose2(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<raypath_geometry::Pose2> {
    let v = vector(obj, name, 0, true)?;
    if v.len() != 3 || !v.iter().all(|c| c.is_finite()) {
        return Err(value_error(
            name,
            format!("expected a pose (x, y, theta) of shape (3,) with finite values, got {v:?}"),
        ));
    }
    Ok(raypath_geometry::Pose2::new(v[0], v[1], v[2]))
}

/// A planar scan from `(B,)` ranges and angles (B ≥ 2, angles evenly spaced and increasing,
/// radians): ranges at or above `max_range` (default infinity) and infinite ranges are
/// no-returns; NaN and negative ranges are refused.
pub fn scan2(
    ranges: &Bound<'_, PyAny>,
    angles: &Bound<'_, PyAny>,
    max_range: Option<f64>,
) -> PyResult<raypath_geometry::Scan2> {
    let ranges = vector(ranges, "ranges", 2, false)?;
    let angles = vector(angles, "angles", 2, false)?;
    if ranges.len() != angles.len() {
        return Err(value_error(
            "angles",
            format!(
                "expected shape ({},) like ranges, got ({},)",
                ranges.len(),
                angles.len()
            ),
        ));
    }
    if let Some(i) = ranges.iter().position(|r| r.is_nan()) {
        return Err(value_error("ranges", format!("value {i} is NaN")));
    }
    if let Some(i) = ranges.iter().position(|&r| r < 0.0) {
        return Err(value_error(
            "ranges",
            format!("value {i} is negative ({})", ranges[i]),
        ));
    }
    if !angles.iter().all(|a| a.is_finite()) {
        return Err(value_error("angles", "not finite"));
    }
    let n = angles.len();
    let step = (angles[n - 1] - angles[0]) / (n - 1) as f64;
    let tolerance = 1e-6 * step.abs().max(1e-9);
    if step <= 0.0
        || angles
            .iter()
            .enumerate()
            .any(|(i, a)| (a - (angles[0] + step * i as f64)).abs() > tolerance.max(1e-9))
    {
        return Err(value_error(
            "angles",
            "must be evenly spaced and increasing",
        ));
    }
    let scan = raypath_geometry::Scan2 {
        angle_min_rad: angles[0],
        angle_increment_rad: step,
        max_range_m: max_range.unwrap_or(f64::INFINITY),
        ranges,
        intensities: None,
    };
    scan.validate().map_err(|e| value_error("max_range", e))?;
    Ok(scan)
}
