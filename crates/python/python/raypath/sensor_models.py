"""Sensor-model maps: per-cell ray statistics for the decay-rate, reflection and log-odds
models (Schaefer 2020, ch. 7), as `raypath map` builds them."""

from ._raypath import SensorMap
from ._raypath import build, load

__all__ = ["SensorMap", "build", "load"]
