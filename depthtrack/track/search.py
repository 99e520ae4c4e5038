"""Stages "predict", "search" and "polish": the model-based part of a frame.

* predict -- the constant-velocity prior's prediction, within the joint limits;
* search -- start from the better of the prediction and the previous pose, then hill
  climbing (:mod:`.hill_climb`) on the MAP energy (:mod:`.energy`);
* polish -- the finest rung of the search once more with the finer tiles.

The three climbers of a tracker (per frame, polish, and the global search's coarser and
longer one) come from the settings in :class:`Climbers`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .hill_climb import HillClimber, default_blocks


@dataclass(frozen=True)
class Climbers:
    """The hill climbers of one tracker.

    Attributes
    ----------
    frame : HillClimber
        The per-frame search (and the refinement of a propagated pose).
    fine : HillClimber
        The polish.
    start : HillClimber
        The global search (first frame, lost track): it starts far off, so its steps are
        :attr:`StartSettings.step_factor` times larger, with more rungs and iterations.
    final : HillClimber
        The final polish (:mod:`.final_polish`) and the heading recheck's polish of a close
        call (:attr:`HeadingSettings.polish_within`): the per-frame blocks with
        :attr:`PolishSettings.final_levels` finer rungs, climbed from the search's finest
        (``level_offset = SearchSettings.levels - 1``).
    """

    frame: HillClimber
    fine: HillClimber
    start: HillClimber
    final: HillClimber

    @classmethod
    def build(cls, settings, fps: float, clip=None) -> "Climbers":
        s, g = settings.search, settings.start
        step_scale = s.step_scale * 25.0 / float(fps)
        blocks = default_blocks(step_scale, s.diagonals, s.pelvis_alone, s.untwist)
        return cls(
            frame=HillClimber(blocks=blocks, levels=s.levels, max_iterations=s.max_iterations,
                              clip=clip),
            fine=HillClimber(blocks=blocks, levels=s.levels,
                             max_iterations=settings.polish.fine_iterations, clip=clip),
            start=HillClimber(blocks=default_blocks(g.step_factor * step_scale, g.diagonals),
                              levels=s.levels + g.extra_levels, max_iterations=g.max_iterations,
                              clip=clip),
            final=HillClimber(blocks=blocks, levels=s.levels + settings.polish.final_levels,
                              max_iterations=settings.polish.final_iterations, clip=clip))


def climb(energy, climber, pose, recorder, start_energy=None, blocks=None, passes: int = 1,
          level_offset: int = 0):
    """Hill-climb ``pose (48,)`` on ``energy``; returns ``(pose (48,), energy float)``.

    The CPU time of the search, less its rendering, is recorded as ``search``.
    """
    with recorder.timed_excluding("search", "render"):
        res = climber.climb(pose, energy, start_energy=start_energy, blocks=blocks, passes=passes,
                            level_offset=level_offset)
    return res.pose, res.energy


def lowest_climb(energy, climber, poses, recorder, passes: int = 1, level_offset: int = 0):
    """Each of ``poses (K, 48)`` climbed by :func:`climb`; returns the lowest climbed
    ``(pose (48,), energy float)`` (the first of equals)."""
    fits = [climb(energy, climber, x, recorder, passes=passes, level_offset=level_offset)
            for x in poses]
    return min(fits, key=lambda f: float(f[1]))


def predict(prior, body, pose, velocity):
    """``(x_pred (48,), v_pred (48,))``: the prior's prediction, clipped to the joint limits."""
    x_pred, v_pred = prior.predict(pose, velocity)
    return body.clip(x_pred), v_pred


def search(energy, climbers, settings, recorder, x_pred, x_prev, climb_it: bool = True):
    """The better start of ``x_pred`` and ``x_prev`` (both (48,)), then hill climbing
    (``climb_it``); returns ``(pose (48,), energy)``."""
    starts = np.stack([x_pred, x_prev])
    e_starts = energy(starts)
    k = int(np.argmin(e_starts))
    x, e = starts[k], float(e_starts[k])
    if climb_it:
        x, e = climb(energy, climbers.frame, x, recorder, start_energy=e,
                     passes=settings.search.passes)
    return x, e


def polish(energy, fine_renderer, climbers, settings, recorder, x):
    """Finest rung of the search again at the fine tile resolution (when configured)."""
    if fine_renderer is None:
        return x, energy.one(x)
    return climb(energy.on(fine_renderer), climbers.fine, x, recorder,
                 level_offset=settings.search.levels - 1)
