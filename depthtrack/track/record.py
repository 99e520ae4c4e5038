"""Where the time went and what was counted: kept outside the stages, like filterpy's Saver.

The stages take a :class:`Recorder` and add to it; they never read it, so whether or not a
branch (a turned twin, a recovery) is kept, its work is counted.
"""
from __future__ import annotations

import time
from contextlib import contextmanager

#: Timed stages (seconds). ``association`` and ``recover`` include the render, search,
#: detect and evidence time spent inside them; ``search`` excludes its render time.
STAGES = ("segment", "render", "detect", "evidence", "search", "association", "init", "recover",
          "heading", "propose", "reach", "reseat", "polish", "final")
#: Counters. ``correspondences`` / ``accepted`` count every correspondence the association
#: tried / kept; ``proposal_correspondences`` / ``proposal_accepted`` those of them from the
#: recogniser's joint proposals (``ProposalSettings.evidence``); ``looks_turned_away`` the
#: fresh looks whose pose faced too far from the track's (``JudgeSettings.look_turn``);
#: ``hidden_limbs`` the limb-frames searched under the hidden-limb pose prior
#: (``EnergySettings.hidden_prior_std``).
COUNTS = ("candidates", "render_calls", "detections", "correspondences", "accepted",
          "recoveries_tried", "recoveries", "frames_without_person", "reinitialisations",
          "proposal_correspondences", "proposal_accepted", "looks_turned_away", "hidden_limbs")


class Recorder:
    """Seconds per stage and counts, with a snapshot taken after the first initialisation."""

    def __init__(self):
        self.timings = {k: 0.0 for k in STAGES}
        self.counts = {k: 0 for k in COUNTS}
        self._after_init = None
        self._counts_after_init = {}
        self._open = []                          # stages being timed, innermost last
        self.candidates_by_stage = {}            # candidates scored inside each stage
        self._by_stage_after_init = {}

    def add(self, stage: str, seconds: float) -> None:
        self.timings[stage] += seconds

    def count(self, name: str, n: int = 1) -> None:
        self.counts[name] += n
        if name == "candidates":
            # charged to the innermost stage that wants them: not render (it only scores
            # them), and search only where no other stage encloses it (every climb is timed
            # as search, the rechecks' and the association's too)
            wanting = [s for s in self._open if s not in ("render", "search")]
            stage = wanting[-1] if wanting else ("search" if "search" in self._open else "other")
            self.candidates_by_stage[stage] = self.candidates_by_stage.get(stage, 0) + n

    @contextmanager
    def timed(self, stage: str):
        t = time.perf_counter()
        self._open.append(stage)
        try:
            yield
        finally:
            self._open.pop()
            self.timings[stage] += time.perf_counter() - t

    @contextmanager
    def timed_excluding(self, stage: str, inner: str):
        """Time ``stage`` minus what ``inner`` accumulated meanwhile (search minus render)."""
        t = time.perf_counter()
        before = self.timings[inner]
        self._open.append(stage)
        try:
            yield
        finally:
            self._open.pop()
            self.timings[stage] += (time.perf_counter() - t) - (self.timings[inner] - before)

    def initialised(self) -> bool:
        """Mark an initialisation done; True for the first one (the snapshot is taken then)."""
        if self._after_init is None:
            self._after_init = dict(self.timings)
            self._counts_after_init = dict(self.counts)
            self._by_stage_after_init = dict(self.candidates_by_stage)
            return True
        return False

    def timing_summary(self, total: float, frames: int) -> dict:
        """Where the time went: totals, and per tracked frame (initialisation excluded).

        Stages (seconds): ``segment`` foreground segmentation; ``render`` candidate rendering
        and scoring on the GPU path (TileRenderer.costs); ``search`` hill-climbing work on
        the CPU (candidate generation, kinematics, prior); ``detect`` part detection;
        ``evidence`` evidence propagation (unscented transform); ``association`` the whole
        association loop (includes its detect, evidence, render and search time);
        ``recover`` global searches after a lost track (includes their render time);
        ``heading`` the front/back recheck (includes its render and search time);
        ``propose`` the part recogniser and its joint proposals; ``polish`` the finest rung
        again at the finer tile (includes its render time); ``final`` the final polish of
        each finished pose (:mod:`.final_polish`; its segmentation and render time too);
        ``other`` = per-frame total minus segment, render, search, detect, evidence, propose
        (frame loading, bookkeeping).
        """
        base = self._after_init or {k: 0.0 for k in self.timings}
        tracked = max(frames - 1, 1)
        init = self.timings["init"]
        per = {k: round(1000 * (v - base.get(k, 0.0)) / tracked, 2)
               for k, v in self.timings.items() if k != "init"}
        tracking = max(total - init, 1e-9)
        per["total"] = round(1000 * tracking / tracked, 2)
        per["other"] = round(per["total"] - sum(per[k] for k in ("segment", "render", "search",
                                                                 "detect", "evidence", "propose")), 2)
        cands = self.counts["candidates"] - self._counts_after_init.get("candidates", 0)
        return {"total_s": round(total, 3), "init_s": round(init, 3), "frames": int(frames),
                "per_frame_ms": per,
                "fps": round(frames / total, 3) if total > 0 else None,
                "fps_excluding_init": round(tracked / tracking, 3) if frames > 1 else None,
                "candidates_per_frame": round(cands / tracked, 1),
                # where they went: the innermost timed stage that asked for them (the rechecks
                # under "heading", "reach" and "reseat", the per-frame climb under "search", "other"
                # outside every stage)
                "candidates_per_frame_by_stage": {
                    k: round((v - self._by_stage_after_init.get(k, 0)) / tracked, 1)
                    for k, v in sorted(self.candidates_by_stage.items())},
                "init_candidates": int(self._counts_after_init.get("candidates", 0))}
