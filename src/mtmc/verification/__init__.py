"""Laser-tracker volumetric verification of machine tools (Aguado et al. 2016, 2017).

The workspace discretised into verification points and the path through them
(:mod:`~mtmc.verification.workspace`), the NC program that moves the machine along it and
an estimate of the measuring time (:mod:`~mtmc.verification.ncprogram`), compensation
tables written from identified error functions (:mod:`~mtmc.verification.compensation`),
the batched least squares (:mod:`~mtmc.verification.lsq`), the identification of the
error functions and the tracker pose from tracker readings
(:mod:`~mtmc.verification.identify`) and the Monte Carlo of a whole verification with its
GUM linearisation (:mod:`~mtmc.verification.simulate`; these three are imported from
their modules, whose function names ``identify`` and ``simulate`` they share).
"""

from mtmc.verification import compensation, ncprogram, workspace
from mtmc.verification.compensation import *  # noqa: F403
from mtmc.verification.ncprogram import *  # noqa: F403
from mtmc.verification.workspace import *  # noqa: F403

__all__: list[str] = [
    *compensation.__all__,
    *ncprogram.__all__,
    *workspace.__all__,
]
