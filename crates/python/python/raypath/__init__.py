"""raypath: lidar mapping, localization, place recognition and SLAM on NumPy arrays.

>>> import raypath
>>> log = raypath.open("intel.clf.bz2")          # doctest: +SKIP
>>> res = raypath.slam(log)                       # doctest: +SKIP
>>> res.map.save("intel.pgm")                     # doctest: +SKIP

Submodules: :mod:`raypath.poles`, :mod:`raypath.planes`, :mod:`raypath.polylines`,
:mod:`raypath.place_recognition`, :mod:`raypath.registration`,
:mod:`raypath.scan_match`, :mod:`raypath.sensor_models`.
"""

from ._raypath import (
    Cloud,
    FormatError,
    InputError,
    Localizer,
    OccupancyMap,
    OccupancyTree,
    OctreeMap,
    PlanarLog,
    RaypathError,
    Scan,
    ScanGraph,
    SlamResult,
    SweepLog,
    __version__,
    open,
    slam,
)
from . import dct_map, place_recognition, planes, poles, polylines, registration, scan_match, sensor_models

__all__ = [
    "Cloud",
    "FormatError",
    "InputError",
    "Localizer",
    "OccupancyMap",
    "OccupancyTree",
    "OctreeMap",
    "PlanarLog",
    "RaypathError",
    "Scan",
    "ScanGraph",
    "SlamResult",
    "SweepLog",
    "__version__",
    "dct_map",
    "open",
    "place_recognition",
    "planes",
    "poles",
    "polylines",
    "registration",
    "scan_match",
    "sensor_models",
    "slam",
]
