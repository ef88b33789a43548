"""3-D scan registration by point-to-plane ICP (KISS-ICP-style thinning and kernel)."""

from ._raypath import Registration
from ._raypath import register

__all__ = ["Registration", "register"]
