"""Where generation tasks run: a small protocol (``submit`` / ``as_completed`` / ``close``)
that the local process pool and Ray both implement, so ``generate`` drives either the same
way and a new executor is one class in ``EXECUTORS``.

A task is ``task(config, index, out) -> manifest entry``. It runs inside ``attempt``, which
turns an exception into a ``Failure`` carrying its one-line summary and its full traceback as
text (a traceback does not survive pickling); a worker process that dies (killed, out of
memory, a crash in native code) is a ``Failure`` with ``worker_died`` set, charged only to
the sequence that was running in it. An exception whose class says ``repeats`` (a cloth
simulation that diverged: the same seed diverges again) is not tried again.
"""
from __future__ import annotations

import os
import traceback
from dataclasses import dataclass
from typing import Callable, Iterator, Protocol

from synmitsuba.errors import ConfigError
from synmitsuba.process import available_cpus, configure_process


@dataclass
class Failure:
    index: int
    summary: str          # one line: "Type: message"
    traceback: str        # the whole traceback, for run.log
    worker_died: bool = False
    repeats: bool = False  # what raised says a retry fails the same way (``ClothError``: deterministic)


@dataclass
class Outcome:
    index: int
    entry: dict | None = None        # the manifest entry when the task succeeded
    failure: Failure | None = None


def attempt(task: Callable, config: dict, index: int, out: str) -> Outcome:
    """Run one task where it is scheduled, catching what it raises (with its traceback)."""
    try:
        return Outcome(index, entry=task(config, index, out))
    except Exception as exc:  # noqa: BLE001 - every failure is reported with its traceback, then retried or listed
        return Outcome(index, failure=Failure(index, f"{type(exc).__name__}: {exc}", traceback.format_exc(),
                                              repeats=bool(getattr(exc, "repeats", False))))


def _died(index: int, why: str) -> Outcome:
    return Outcome(index, failure=Failure(index, f"a worker died ({why})", "", worker_died=True))


def worker_setup(threads: int, parent: int | None = None) -> None:
    """A worker process owns itself: opt into the process settings, size drjit's threads. It
    leaves Ctrl-C to the parent (which stops it) and, on Linux, dies with the parent: a worker
    orphaned by a killed parent would otherwise render on and write after the run ended."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent(parent)
    configure_process()
    os.environ["SYNMITSUBA_THREADS"] = str(threads)


def _die_with_parent(parent: int | None) -> None:
    import sys
    if parent is None or not sys.platform.startswith("linux"):
        return
    import ctypes
    import signal
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent:  # the parent was gone before the request took hold
        os._exit(1)


class Executor(Protocol):
    def submit(self, index: int) -> None: ...
    def as_completed(self) -> Iterator[Outcome]: ...
    def close(self) -> None: ...


class LocalPool:
    """A spawn process pool with at most ``workers`` tasks in flight, so a pool that breaks
    held only running tasks. When it breaks with several running, they are run again one at a
    time, uncharged: the one whose pool then breaks alone is the one charged."""

    def __init__(self, task: Callable, config: dict, out: str, workers: int, address: str | None = None):
        self.task, self.config, self.out, self.workers = task, config, out, max(1, workers)
        self.threads = max(1, available_cpus() // self.workers)
        self.queue: list[int] = []
        self.suspects: list[int] = []   # in flight when a shared pool broke: each reruns alone
        self.running: dict = {}         # future -> index
        self.pool = None

    def submit(self, index: int) -> None:
        self.queue.append(index)

    def _pool(self):
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor
        if self.pool is None:
            self.pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context("spawn"),
                                            initializer=worker_setup, initargs=(self.threads, os.getpid()))
        return self.pool

    def _fill(self) -> None:
        """Start queued tasks up to the worker count (one at a time while suspects remain)."""
        from concurrent.futures.process import BrokenProcessPool
        limit = 1 if self.suspects else self.workers
        while len(self.running) < limit and (self.suspects or self.queue):
            source = self.suspects or self.queue
            i = source.pop(0)
            try:
                fut = self._pool().submit(attempt, self.task, self.config, i, self.out)
            except BrokenProcessPool:  # it broke after the last wait: the tasks still running will say so
                source.insert(0, i)
                if self.running:
                    return
                if self.pool is not None:
                    self.pool.shutdown(wait=False, cancel_futures=True)
                self.pool = None
                continue
            self.running[fut] = i

    def as_completed(self) -> Iterator[Outcome]:
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool
        self._fill()
        while self.running:
            finished, _ = wait(list(self.running), return_when=FIRST_COMPLETED)
            broken = []
            for fut in finished:
                i = self.running.pop(fut)
                try:
                    yield fut.result()
                except BrokenProcessPool as exc:
                    broken.append((i, str(exc)))
            if broken:
                yield from self._after_break(broken)
            self._fill()

    def _after_break(self, broken: list) -> Iterator[Outcome]:
        """The pool is gone with everything in it: a lone task is charged, several become suspects."""
        lost = broken + [(i, "") for i in self.running.values()]
        self.running.clear()
        if self.pool is not None:
            self.pool.shutdown(wait=False, cancel_futures=True)
        self.pool = None
        if len(lost) == 1:
            yield _died(*lost[0])
        else:
            self.suspects.extend(sorted(i for i, _ in lost))

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
            self.pool = None


class RayPool:
    """Ray tasks (a local Ray, or a cluster at ``address``); Ray reports a dead worker on the
    task that was running in it, so it is charged directly. Retries are ``generate``'s."""

    def __init__(self, task: Callable, config: dict, out: str, workers: int, address: str | None = None):
        try:
            import ray
        except ImportError:
            raise ConfigError("--executor", "ray", "Ray is not installed: pip install 'synmitsuba[ray]'") from None
        self.ray, self.task, self.config, self.out = ray, task, config, out
        self.started = not ray.is_initialized()
        if self.started:
            ray.init(address=address, num_cpus=None if address else available_cpus(), include_dashboard=False,
                     log_to_driver=False)
        threads = max(1, available_cpus() // max(1, workers))
        self.remote = ray.remote(num_cpus=threads, max_retries=0)(_ray_attempt).options(
            runtime_env={"env_vars": {"SYNMITSUBA_THREADS": str(threads)}})
        self.refs: dict = {}

    def submit(self, index: int) -> None:
        self.refs[self.remote.remote(self.task, self.config, index, self.out)] = index

    def as_completed(self) -> Iterator[Outcome]:
        while self.refs:
            ready, _ = self.ray.wait(list(self.refs), num_returns=1)
            i = self.refs.pop(ready[0])
            try:
                yield self.ray.get(ready[0])
            except Exception as exc:  # noqa: BLE001 - the worker died or Ray lost the task
                yield _died(i, f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}")

    def close(self) -> None:
        if self.started:
            self.ray.shutdown()


def _ray_attempt(task: Callable, config: dict, index: int, out: str) -> Outcome:
    configure_process()
    return attempt(task, config, index, out)


EXECUTORS: dict[str, Callable[..., Executor]] = {"local": LocalPool, "ray": RayPool}
