"""Pole landmarks from 3-D lidar scans (Schaefer 2020, ch. 12)."""

from ._raypath import Poles
from ._raypath import extract

__all__ = ["Poles", "extract"]
