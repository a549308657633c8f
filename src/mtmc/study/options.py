"""The options of a study's Monte Carlo run beyond ``trials`` and ``seed``, checked in one place.

Two options change how a study's Monte Carlo run goes, whichever way they are given
(``[run]`` in the study file, ``mtmc run --adaptive / --nan-policy``, or
:meth:`mtmc.study.Study.run`):

- ``adaptive``: the number of trials is chosen by the adaptive procedure of JCGM 101
  §7.9.4, which stops when twice the standard deviations of the block estimates, standard
  uncertainties and coverage-interval endpoints of every component of every output the
  study reports are at most the numerical tolerance of its ``u`` to ``ndig`` significant
  digits (JCGM 101 §7.9.2);
- ``nan_policy``: a trial whose model value is NaN or infinite stops the run
  (``"raise"``) or is left out of every output and counted (``"omit"``).

A kind offers those of them its class names in ``Study.run_options``; :func:`unsupported_option`
says which asked-for option a kind does not offer and why, and :func:`run_record` is what a
result says of its run (``run`` of ``result.json``).
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol

from mtmc.study.settings import RunSettings

__all__ = ["ADAPTIVE", "NAN_POLICY", "mc_run_record", "run_record", "unsupported_option"]

#: The name of the option of an adaptive run (JCGM 101 §7.9).
ADAPTIVE = "adaptive"
#: The name of the option that leaves out trials whose model value is not finite.
NAN_POLICY = "nan_policy"


class OffersOptions(Protocol):
    """What :func:`unsupported_option` reads of a study (:class:`mtmc.study.Study`)."""

    kind: ClassVar[str]
    run_options: ClassVar[frozenset[str]]
    no_adaptive: ClassVar[str]


def unsupported_option(study: OffersOptions, settings: RunSettings) -> tuple[str, str] | None:
    """The first option of ``settings`` that the kind of ``study`` does not offer.

    Parameters
    ----------
    study : Study
        The study; ``type(study).run_options`` names what its kind offers.
    settings : RunSettings
        The settings of the run.

    Returns
    -------
    tuple of (str, str) or None
        ``(key, message)``: the ``[run]`` key that asked for it (``"trials"`` for
        ``trials = "adaptive"``, ``"nan_policy"``) and a sentence saying why it is
        refused and what to give instead; None when the kind offers every option asked.
    """
    offered = type(study).run_options
    kind = type(study).kind
    if settings.adaptive and ADAPTIVE not in offered:
        why = type(study).no_adaptive or "its Monte Carlo run has a fixed number of trials"
        return (
            "trials",
            f"a {kind} study has no adaptive Monte Carlo (JCGM 101 §7.9): {why}; expected a "
            "number of trials",
        )
    if settings.nan_policy != "raise" and NAN_POLICY not in offered:
        return (
            "nan_policy",
            f"a {kind} study cannot leave out trials: nan_policy = {settings.nan_policy!r} is "
            "not offered for it; expected 'raise'",
        )
    return None


def mc_run_record(settings: RunSettings, mc: Any) -> dict[str, Any]:
    """:func:`run_record` of a Monte Carlo result (its trials, omitted, blocks, tolerance)."""
    return run_record(settings, mc.trials, mc.omitted, blocks=mc.blocks, tolerance=mc.tolerance)


def run_record(
    settings: RunSettings,
    trials: int,
    omitted: int = 0,
    *,
    blocks: int | None = None,
    tolerance: float | None = None,
) -> dict[str, Any]:
    """What a result says of its Monte Carlo run (``run`` of ``result.json``).

    Parameters
    ----------
    settings : RunSettings
        The settings of the run.
    trials : int
        The trials run (chosen by the procedure for an adaptive run), those left out
        included.
    omitted : int
        Trials left out because a model value was NaN or infinite (``nan_policy =
        "omit"``).
    blocks, tolerance : optional
        For an adaptive run: the number of blocks of the procedure and the numerical
        tolerance δ it met (JCGM 101 §7.9.4).

    Returns
    -------
    dict
        ``adaptive``, ``trials``, ``omitted``, ``nan_policy``, ``ndig``, and for an
        adaptive run ``blocks`` and ``tolerance``.

    Examples
    --------
    >>> from mtmc.study.settings import RunSettings
    >>> run_record(RunSettings(nan_policy="omit"), 1000, 3)
    {'adaptive': False, 'trials': 1000, 'omitted': 3, 'nan_policy': 'omit', 'ndig': 2}
    """
    out: dict[str, Any] = {
        "adaptive": settings.adaptive,
        "trials": int(trials),
        "omitted": int(omitted),
        "nan_policy": settings.nan_policy,
        "ndig": settings.ndig,
    }
    if settings.adaptive:
        out["blocks"] = blocks
        out["tolerance"] = tolerance
    return out
