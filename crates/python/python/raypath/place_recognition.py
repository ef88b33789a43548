"""Place recognition: IBuILD, DBoW2-style and Scan Context databases with one interface
(`add`, `query`, `add_and_query`) over planar scans, point clouds and images."""

from ._raypath import Dbow, Ibuild, ScanContext

__all__ = ["Dbow", "Ibuild", "ScanContext"]
