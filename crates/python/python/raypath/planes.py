"""Plane extraction from organized 3-D scans (PPE, Schaefer 2020, ch. 11)."""

from ._raypath import Plane
from ._raypath import ppe

__all__ = ["Plane", "ppe"]
