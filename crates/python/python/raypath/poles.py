"""Pole landmarks from 3-D lidar scans (Schaefer 2020, ch. 12): extraction, pole maps and
the pole particle filter."""

from ._raypath import PoleFilter, Poles
from ._raypath import extract
from ._raypath import map  # noqa: A004 - `raypath.poles.map`, as `raypath poles map`

__all__ = ["PoleFilter", "Poles", "extract", "map"]
