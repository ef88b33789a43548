//! # raypath-python
//!
//! The Python package `raypath` (built with maturin; `pip install maturin && maturin develop
//! -m crates/python/Cargo.toml`): NumPy arrays in and out over the raypath crates. This crate
//! is the native module `raypath._raypath`; the package around it (`python/raypath`) gives
//! it its namespaces (`raypath.poles`, `raypath.planes`, …), type stubs and `py.typed`.
//!
//! Every binding calls the library crates' public functions, as the `raypath` command line
//! does, so results equal the command line's. Bad arguments raise `ValueError` naming the
//! argument and the shape expected; errors of the Rust side raise `raypath.FormatError`
//! (files, with `path`, `line`, `byte`), `raypath.InputError` (data an algorithm cannot use)
//! or `FileNotFoundError`. Long work runs with the GIL released.

mod arrays;
mod dct_map;
mod errors;
mod io;
mod localizer;
mod octomap;
mod octree;
pub mod pipeline;
mod place;
mod planes;
mod pole_filter;
mod poles;
mod polylines;
mod registration;
mod scan_match;
mod sensor_map;
mod slam;

use pyo3::prelude::*;

/// The native module: every class and function, the package re-exports them.
#[pymodule]
fn _raypath(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_function(wrap_pyfunction!(io::open, m)?)?;
    m.add_class::<io::Cloud>()?;
    m.add_class::<io::Scan>()?;
    m.add_class::<io::PlanarLog>()?;
    m.add_class::<io::SweepLog>()?;
    m.add_class::<octomap::OctreeMap>()?;
    m.add_class::<octomap::ScanGraph>()?;
    m.add_function(wrap_pyfunction!(slam::slam, m)?)?;
    m.add_class::<slam::SlamResult>()?;
    m.add_class::<slam::OccupancyMap>()?;
    m.add_class::<octree::OccupancyTree>()?;
    m.add_function(wrap_pyfunction!(poles::extract, m)?)?;
    m.add_class::<poles::Poles>()?;
    m.add_function(wrap_pyfunction!(poles::pole_map, m)?)?;
    m.add_class::<pole_filter::PoleFilter>()?;
    m.add_function(wrap_pyfunction!(planes::ppe, m)?)?;
    m.add_class::<planes::Plane>()?;
    m.add_function(wrap_pyfunction!(polylines::ple, m)?)?;
    m.add_class::<polylines::Polyline>()?;
    m.add_class::<place::ScanContext>()?;
    m.add_class::<place::Ibuild>()?;
    m.add_class::<place::Dbow>()?;
    m.add_function(wrap_pyfunction!(registration::register, m)?)?;
    m.add_class::<registration::Registration>()?;
    m.add_class::<registration::Odometry>()?;
    m.add_class::<scan_match::ScanMatcher>()?;
    m.add_function(wrap_pyfunction!(scan_match::match_log, m)?)?;
    m.add_class::<sensor_map::SensorMap>()?;
    m.add_function(wrap_pyfunction!(sensor_map::build, m)?)?;
    m.add_function(wrap_pyfunction!(sensor_map::load, m)?)?;
    m.add_class::<localizer::Localizer>()?;
    m.add_class::<dct_map::DctMap>()?;
    m.add_function(wrap_pyfunction!(dct_map::fit, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
