"""3-D scan registration by point-to-plane ICP (KISS-ICP-style thinning and kernel), and
lidar odometry over a sequence."""

from ._raypath import Odometry, Registration
from ._raypath import register

__all__ = ["Odometry", "Registration", "register"]
