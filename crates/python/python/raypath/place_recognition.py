"""Place recognition on 3-D scans (Scan Context)."""

from ._raypath import ScanContext

__all__ = ["ScanContext"]
