"""Continuous DCT decay-rate maps (Schaefer 2020, ch. 9), as `raypath dct-map` fits them."""

from ._raypath import DctMap
from ._raypath import fit

__all__ = ["DctMap", "fit"]
