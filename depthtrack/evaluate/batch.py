"""Run the sequences of ``depthtrack eval`` one after another, in a process pool, or on Dask.

One task per sequence, the same function (:func:`run_sequence`) in all three executors:

* ``serial``  -- in this process, in order (the default);
* ``workers`` -- ``--workers N``: a pool of N processes started with ``spawn`` (never
  ``fork``: a forked child would share the parent's OpenGL and BLAS state), each with its
  own EGL context (made on first use) and BLAS limited to one thread;
* ``dask``    -- ``--dask ADDRESS`` (a running scheduler, ``tcp://host:8786``) or
  ``--dask local`` (a ``distributed.LocalCluster`` of worker processes, one thread each,
  ``--workers`` of them, default 2). Workers must import the same depthtrack and see the
  sequence paths (a shared file system); start them with one thread each (``dask worker
  ADDRESS --nthreads 1 --nworkers N``): a process runs one sequence at a time anyway,
  since its OpenGL context serves one thread.

A task opens its sequence, tracks it with every method, scores it and, when asked, writes
each track to ``TRACKS/NAME/METHOD/`` atomically. It never raises: a failure (bad input,
or any other error) comes back as a :class:`SequenceFailure` and the other sequences go
on. Results are returned in the order the sequences were given, whatever order they
finished in, so every executor gives the same :class:`~depthtrack.evaluate.runs.Evaluation`.
Each task runs with BLAS capped to one thread in every executor (threadpoolctl), so the
serial run does the same arithmetic as the parallel ones: tracking is deterministic and
the figures agree exactly (only ``fps``, a timing, differs).
"""
from __future__ import annotations

import multiprocessing
import threading
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError

EXECUTORS = ("serial", "workers", "dask")

_PROCESS_LOCK = threading.Lock()

#: How long to try reaching a Dask scheduler before giving up.
DASK_CONNECT_TIMEOUT = "20s"


@dataclass(frozen=True)
class SequenceTask:
    """What one task needs (plain, picklable values).

    Attributes
    ----------
    index : int
        Position among the given sequences (results are put back in this order).
    path : str
    name : str
    methods : tuple of str
    likelihood : str
    tracks_dir : str or None
        Where to write ``NAME/METHOD/`` track outputs, if anywhere.
    progress : bool
        A per-frame progress meter on a terminal (serial runs only: parallel meters garble).
    open_options : dict
        Reader options for :func:`depthtrack.io.registry.open_sequence` (``topic``, ...).
    settings : TrackerSettings or None
        The tracker's settings (a frozen dataclass, picklable; None = the defaults).
    """

    index: int
    path: str
    name: str
    methods: tuple
    likelihood: str
    tracks_dir: str | None = None
    progress: bool = False
    open_options: dict = field(default_factory=dict)
    settings: object = None


@dataclass
class SequenceFailure:
    """A sequence that could not be evaluated.

    Attributes
    ----------
    name, path : str
    message : str
        One line: what went wrong.
    bad_input : bool
        True for an :class:`InputError` (the sequence's own fault), False for a crash.
    detail : str
        The traceback of a crash ("" for bad input).
    """

    name: str
    path: str
    message: str
    bad_input: bool
    detail: str = ""


def evaluate_sequence(task: SequenceTask) -> list:
    """Track one sequence with every method and score it: ``list of MethodResult``.

    Raises what goes wrong (:func:`run_sequence` turns that into a failure record).
    """
    from threadpoolctl import threadpool_limits

    from . import runs

    # one task at a time per process: the process's one GL context is not shared between
    # threads (a Dask worker started with --nthreads 2 would otherwise run two at once)
    with _PROCESS_LOCK, threadpool_limits(limits=1):
        from .fit import person_masks

        seq = runs.open_with_ground_truth(task.path, require=False, **task.open_options)
        masks = person_masks(seq)          # segmented once per sequence, for all its methods
        results = []
        for method in task.methods:
            joints, poses, body, seconds, summary = runs.track_sequence(
                seq, method, task.likelihood, not task.progress, settings=task.settings)
            result = runs.score(task.name, method, seq, joints, poses, body, seconds,
                                masks=masks, wall_seconds=runs.summary_wall_seconds(summary))
            result.track_summary = dict(summary)
            if task.tracks_dir is not None:
                from ..io.track_output import write_track
                write_track(Path(task.tracks_dir) / task.name / method, joints, poses, body.pose_names,
                            body, seq.fps, dict(summary, sequence=str(seq.path)))
            results.append(result)
    return results


def run_sequence(task: SequenceTask):
    """The task function of every executor: :func:`evaluate_sequence`, failures returned, not raised.

    Returns
    -------
    (index, list of MethodResult) or (index, SequenceFailure)
    """
    try:
        return task.index, evaluate_sequence(task)
    except InputError as exc:
        return task.index, SequenceFailure(task.name, task.path, str(exc), True)
    except Exception as exc:  # a task never takes the batch down; the caller reports it
        return task.index, SequenceFailure(task.name, task.path, f"{type(exc).__name__}: {exc}", False,
                                           traceback.format_exc())


def _limit_blas_threads():
    """Pool initializer: one BLAS thread per worker process (N processes share the cores)."""
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1)


def _serial(tasks, keep_going):
    for task in tasks:
        # stopping at the first failure: let it raise here with its own traceback
        yield run_sequence(task) if keep_going else (task.index, evaluate_sequence(task))


def _process_pool(tasks, workers):
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_limit_blas_threads) as pool:
        futures = {pool.submit(run_sequence, t): t for t in tasks}
        for future in as_completed(futures):
            task = futures[future]
            try:
                yield future.result()
            except Exception as exc:   # the worker process died (killed, out of memory)
                yield task.index, SequenceFailure(task.name, task.path,
                                                  f"worker process failed: {type(exc).__name__}: {exc}", False)


def _dask(tasks, address, workers):
    try:
        from distributed import Client, LocalCluster
        from distributed import as_completed as dask_completed
    except ImportError:
        raise InputError(None, "--dask needs Dask distributed: pip install 'dask[distributed]'") from None
    cluster = None
    try:
        if address == "local":
            cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        else:
            try:
                client = Client(address, timeout=DASK_CONNECT_TIMEOUT)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(None, f"cannot reach the Dask scheduler at {address!r} ({exc})") from None
        with client:
            # pure=False: a task is a run, not a cacheable function of its arguments
            futures = {client.submit(run_sequence, t, pure=False, key=f"depthtrack-eval-{t.index}-{t.name}"): t
                       for t in tasks}
            for future in dask_completed(futures):
                task = futures[future]
                try:
                    yield future.result()
                except Exception as exc:   # a worker lost, or the task could not be shipped
                    yield task.index, SequenceFailure(task.name, task.path,
                                                      f"Dask task failed: {type(exc).__name__}: {exc}", False)
    finally:
        if cluster is not None:
            cluster.close()


def run_tasks(tasks, executor: str = "serial", workers: int | None = None, address: str | None = None,
              log=None, keep_going: bool = True):
    """Run sequence tasks and gather their outcomes in task order.

    Parameters
    ----------
    tasks : list of SequenceTask
    executor : {"serial", "workers", "dask"}
    workers : int or None
        Processes for ``"workers"`` (required there); worker processes of ``--dask local``.
    address : str or None
        ``"local"`` or a scheduler address, for ``"dask"``.
    log : callable(str) or None
        One line per finished sequence, as it finishes: ``[k/n] NAME: ...``.
    keep_going : bool
        True: failures are returned and the other sequences run on. False: the first
        failure raises (an :class:`InputError` for bad input).

    Returns
    -------
    results : list of MethodResult
        In task order, then method order.
    failures : list of SequenceFailure
        In task order.
    """
    log = log or (lambda line: None)
    if executor == "serial":
        outcomes = _serial(tasks, keep_going)
    elif executor == "workers":
        if not workers or workers < 1:
            raise InputError(None, f"--workers must be at least 1, not {workers}")
        outcomes = _process_pool(tasks, workers)
    elif executor == "dask":
        if not address:
            raise InputError(None, "--dask needs an address: 'local' or tcp://HOST:8786")
        outcomes = _dask(tasks, address, workers)
    else:
        raise ValueError(f"executor must be one of {EXECUTORS}, not {executor!r}")
    by_index = {}
    start = time.perf_counter()
    for done, (index, outcome) in enumerate(outcomes, start=1):
        by_index[index] = outcome
        name = tasks[[t.index for t in tasks].index(index)].name
        if isinstance(outcome, SequenceFailure):
            if not keep_going:
                if outcome.bad_input:
                    raise InputError(None, outcome.message)
                raise RuntimeError(f"{outcome.path}: {outcome.message}\n{outcome.detail}")
            log(f"[{done}/{len(tasks)}] {name}: FAILED: {outcome.message}")
        else:
            from .runs import _line
            for result in outcome:
                log(f"[{done}/{len(tasks)}] {_line(result)}  ({time.perf_counter() - start:.1f} s)")
    results, failures = [], []
    for task in tasks:
        outcome = by_index[task.index]
        if isinstance(outcome, SequenceFailure):
            failures.append(outcome)
        else:
            results.extend(outcome)
    return results, failures


__all__ = ["EXECUTORS", "SequenceTask", "SequenceFailure", "evaluate_sequence", "run_sequence", "run_tasks"]
