"""Process-wide settings that the library never changes on its own.

Library code leaves the interpreter as it found it: no thread caps, no garbage-collector
tuning, no plotting backend, no environment variables. An application that owns its process
(the ``synmitsuba`` CLI, a generation worker) opts in once with ``configure_process()``:

- ``collect_before_load``: a full ``gc.collect()`` before each Mitsuba scene load, so garbage
  from an earlier scene is not traced into the new scene's kernels (saves a ~1 s recompile a
  few frames later);
- ``freeze_after_model_load``: ``gc.freeze()`` once the body model is loaded (about 400,000
  long-lived objects that every collection would otherwise scan: 0.4 s a scene load);
- ``torch_threads``: torch's intra-op threads for the body model (anny), set exactly (not
  capped at the environment's default) when it loads, so subjects are built bit for bit alike
  in every worker.

(Figures are drawn on bare matplotlib ``Figure`` objects, so no plotting backend is ever set.)

A training job that embeds synmitsuba keeps its own settings unless it calls this.
"""
from __future__ import annotations

import os
from dataclasses import dataclass


@dataclass
class ProcessSettings:
    collect_before_load: bool = False
    freeze_after_model_load: bool = False
    torch_threads: int | None = None
    forward_only_kernels: bool = False


SETTINGS = ProcessSettings()


def available_cpus() -> int:
    """The CPUs this process may use: its affinity mask, capped by a cgroup v2 quota
    (containers, slurm), which affinity does not show. The one count that drjit's threads,
    the generation pool and Ray's tasks are sized from."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # macOS
        n = os.cpu_count() or 1
    quota = _cgroup_cpus()
    return max(1, min(n, quota) if quota else n)


def _cgroup_cpus() -> int | None:
    try:
        with open("/sys/fs/cgroup/cpu.max") as fh:
            quota, period = fh.read().split()[:2]
        return None if quota == "max" else max(1, int(int(quota) / int(period)))
    except (OSError, ValueError):
        return None


def configure_process(torch_threads: int | None = 2) -> ProcessSettings:
    """Opt this process into the settings above (the CLI and generation workers call it);
    returns them. ``torch_threads``: the body model's torch threads (None: torch's own)."""
    SETTINGS.collect_before_load = True
    SETTINGS.freeze_after_model_load = True
    SETTINGS.torch_threads = torch_threads
    SETTINGS.forward_only_kernels = True
    return SETTINGS


def apply_warp_settings() -> None:
    """The process's Warp opt-ins (``forward_only_kernels``), applied by the stage about to
    make Warp modules; nothing unless the process opted in."""
    if SETTINGS.forward_only_kernels:
        import warp
        warp.config.enable_backward = False
