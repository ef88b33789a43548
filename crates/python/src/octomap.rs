//! OctoMap files opened by `raypath.open`: an occupancy tree (`.bt`) as its leaves, a scan
//! graph (`.graph`) as its scans, poses and edges.

use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use raypath_io::octomap::{OcTree, ScanGraph as Graph};

use crate::arrays::{matrix, poses3, vec1};
use crate::io::{Cloud, normalize};

/// An OctoMap occupancy tree read from a `.bt` file, as its leaves (cubes of known
/// occupancy; pruned leaves are larger than the resolution).
#[pyclass(module = "raypath", name = "OctreeMap", frozen)]
pub struct OctreeMap {
    pub(crate) tree: OcTree,
}

#[pymethods]
impl OctreeMap {
    /// Leaf centres, `(K, 3)` float64, metres.
    #[getter]
    fn centers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let leaves = &self.tree.leaves;
        let flat = leaves
            .iter()
            .flat_map(|l| [l.center.x, l.center.y, l.center.z])
            .collect();
        matrix(py, flat, leaves.len(), 3)
    }

    /// Leaf edge lengths, `(K,)` float64, metres.
    #[getter]
    fn sizes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.tree.leaves.iter().map(|l| l.size_m).collect())
    }

    /// True for occupied leaves, `(K,)` bool.
    #[getter]
    fn occupied<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        vec1(py, self.tree.leaves.iter().map(|l| l.occupied).collect())
    }

    /// Leaf depths, `(K,)` uint8 (16 = finest).
    #[getter]
    fn depths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u8>> {
        vec1(py, self.tree.leaves.iter().map(|l| l.depth).collect())
    }

    /// Edge of the finest voxels, metres.
    #[getter]
    fn resolution(&self) -> f64 {
        self.tree.resolution_m
    }

    /// The tree type of the header (`OcTree`, …).
    #[getter]
    fn tree_type(&self) -> String {
        self.tree.id.clone()
    }

    /// Number of occupied leaves.
    #[getter]
    fn occupied_leaves(&self) -> usize {
        self.tree.occupied_leaves()
    }

    /// Number of inner nodes (root included).
    #[getter]
    fn inner_nodes(&self) -> u64 {
        self.tree.inner_nodes
    }

    /// `(min, max)` corners of the occupied leaves' cubes (all leaves with
    /// `occupied_only=False`).
    #[pyo3(signature = (occupied_only = true))]
    fn bounding_box(&self, occupied_only: bool) -> ([f64; 3], [f64; 3]) {
        let b = self.tree.bounding_box(occupied_only);
        ([b.min.x, b.min.y, b.min.z], [b.max.x, b.max.y, b.max.z])
    }

    fn __len__(&self) -> usize {
        self.tree.leaves.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "OctreeMap({} leaves, {} occupied, resolution {} m)",
            self.tree.leaves.len(),
            self.tree.occupied_leaves(),
            self.tree.resolution_m
        )
    }
}

/// An OctoMap scan graph read from a `.graph` file: scans with their sensor poses and the
/// edges between them. Index it for a scan's `Cloud` (sensor frame).
#[pyclass(module = "raypath", name = "ScanGraph", frozen)]
pub struct ScanGraph {
    pub(crate) graph: Graph,
}

#[pymethods]
impl ScanGraph {
    /// `world_from_sensor` of every scan, `(N, 4, 4)`.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let poses: Vec<_> = self
            .graph
            .nodes
            .iter()
            .map(|n| n.world_from_sensor)
            .collect();
        poses3(py, &poses)
    }

    /// Node ids, `(N,)` int64.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        vec1(
            py,
            self.graph.nodes.iter().map(|n| i64::from(n.id)).collect(),
        )
    }

    /// Edges as node ids, `(E, 2)` int64.
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let e = &self.graph.edges;
        let flat = e
            .iter()
            .flat_map(|e| [i64::from(e.first_id), i64::from(e.second_id)])
            .collect();
        matrix(py, flat, e.len(), 2)
    }

    /// The constraint of every edge, `first_from_second`, `(E, 4, 4)`.
    #[getter]
    fn edge_poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let poses: Vec<_> = self
            .graph
            .edges
            .iter()
            .map(|e| e.first_from_second)
            .collect();
        poses3(py, &poses)
    }

    /// Edge weights, `(E,)`.
    #[getter]
    fn edge_weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.graph.edges.iter().map(|e| e.weight).collect())
    }

    fn __len__(&self) -> usize {
        self.graph.nodes.len()
    }

    fn __getitem__(&self, index: isize) -> PyResult<Cloud> {
        let i = normalize(index, self.graph.nodes.len())?;
        Ok(Cloud {
            cloud: self.graph.nodes[i].points.clone(),
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "ScanGraph({} scans, {} edges, {} points)",
            self.graph.nodes.len(),
            self.graph.edges.len(),
            self.graph.num_points()
        )
    }
}
