"""Polyline extraction from planar laser scans (PLE, Schaefer 2020, ch. 10)."""

from ._raypath import Polyline
from ._raypath import ple

__all__ = ["Polyline", "ple"]
