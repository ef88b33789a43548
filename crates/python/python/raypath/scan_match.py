"""Hector-style scan-to-map matching of planar scans (the matcher of `raypath scan-match`)."""

from ._raypath import ScanMatcher
from ._raypath import match_log

__all__ = ["ScanMatcher", "match_log"]
