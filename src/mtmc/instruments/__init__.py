"""Measuring instruments of a volumetric verification: the laser tracker and multilateration."""

from mtmc.instruments.laser_tracker import (
    LaserTracker,
    TrackerLimits,
    TrackerNoise,
    VisibilityFailure,
    VisibilityReport,
    cartesian,
    spherical,
    spherical_jacobian,
    visibility,
)
from mtmc.instruments.multilateration import (
    Multilateration,
    datum_frame,
    datum_pose,
    self_calibrate,
    trilaterate,
    trilateration_covariance,
)

__all__ = [
    "LaserTracker",
    "TrackerLimits",
    "TrackerNoise",
    "VisibilityFailure",
    "VisibilityReport",
    "cartesian",
    "spherical",
    "spherical_jacobian",
    "visibility",
    "Multilateration",
    "datum_frame",
    "datum_pose",
    "self_calibrate",
    "trilaterate",
    "trilateration_covariance",
]
