"""Sharded, resumable dataset generation: one task per sequence, seeded from (seed, index) only.

Layout: ``OUT/seq_XXXXXX/`` holds a sequence's ``scene.json`` and its samples
(``f0000_cam0.exr/.json/.png``, ...). A task writes into ``seq_XXXXXX.partial/`` and renames
it when the sequence is complete; only then does the parent append the sequence's line to
``OUT/manifest.jsonl``. A rerun skips sequences in the manifest and redoes the rest
(partial folders are removed first). Timings and host names go to ``OUT/run.log``, never into
sample files, so the files are byte-identical whoever renders them.
"""
from __future__ import annotations

import json
import os
import shutil
import socket
import time
from dataclasses import dataclass, field
from typing import Callable

from synmitsuba.errors import ConfigError
from synmitsuba.generate.config import GenerateConfig
from synmitsuba.generate.executors import EXECUTORS, Failure
from synmitsuba.io.files import ACTIVE_TEMPORARIES, atomic_path
from synmitsuba.rendering.photo import Photo
from synmitsuba.seeds import effects_rng, render_seed, sequence_rng


def sequence_spec(cfg: GenerateConfig, index: int):
    """Sequence ``index``'s scene as a ``SceneSpec``: the config's scene file, or a composed
    scene; every draw from ``sequence_rng(cfg.seed, index)``."""
    rng = sequence_rng(cfg.seed, index)
    if cfg.scene is not None:
        from synmitsuba.compose.scenefile_spec import scene_spec
        return scene_spec(cfg.scene, cfg.scene, rng, seed=cfg.seed)
    from synmitsuba.compose.composition import compose_scene
    return compose_scene(cfg.compose, rng, seed=cfg.seed)


def sequence_effects(cfg: GenerateConfig, index: int) -> tuple[float, Photo | None]:
    """Sequence ``index``'s camera effects, drawn in this order from ``effects_rng`` (nothing for
    what is off): its exposure as a share of the frame interval (``render.shutter_deg`` / 360)
    and its photo development (``render.photo``; None when off)."""
    rng = effects_rng(cfg.seed, index)
    lo, hi = cfg.render.shutter_deg
    shutter = float(rng.uniform(lo, hi)) / 360.0 if hi > 0 else 0.0
    return shutter, (cfg.render.photo.draw(rng) if cfg.render.photo.enabled else None)


def sequence_frames(cfg: GenerateConfig, n_frames: int) -> list[int]:
    """The clip frames a sequence renders: every ``stride``-th, at most ``frames`` of them."""
    frames = list(range(0, n_frames, cfg.stride))
    return frames if cfg.frames is None else frames[:cfg.frames]


def write_sequence(spec, cfg: GenerateConfig, index: int, folder: str, bar=None) -> list[str]:
    """Render and label ``spec``'s frames as ``cfg`` says, writing ``scene.json`` and
    ``fFFFF_<view>`` samples into ``folder``; returns the sample stems."""
    from synmitsuba.engine.build import release_memory
    from synmitsuba.io.exr import write_sample
    from synmitsuba.pipeline import render_sequence
    with open(os.path.join(folder, "scene.json"), "w") as fh:
        fh.write(spec.to_json(indent=1))
    r, stems = cfg.render, []
    shutter, photo = sequence_effects(cfg, index)
    try:
        for f, view, sample in render_sequence(spec, frames=sequence_frames(cfg, spec.n_frames), spp=r.spp,
                                               seed=render_seed(cfg.seed, index), annotate=cfg.annotate,
                                               body_models=cfg.smplx, flow="rendered" if cfg.flow == "rendered" else 1,
                                               max_depth=r.max_depth, sampler=r.sampler, denoise=r.denoise,
                                               shutter=shutter, subframes=r.subframes, photo=photo):
            sample.meta.update(sequence=index)
            stem = f"f{f:04d}_{view}"
            write_sample(sample, os.path.join(folder, stem))
            stems.append(stem)
            if bar is not None:
                bar.update(1)
    finally:
        release_memory()  # this sequence's kernels and buffers: the next one has other BSDFs
    return stems


def run_sequence(config: dict, index: int, out: str) -> dict:
    """Compose (or read), render and write sequence ``index``: the one task of a generation
    (``config`` as a plain dict so it crosses process boundaries). Returns the sequence's
    manifest entry."""
    cfg = GenerateConfig.from_dict(config, "")
    name = f"seq_{index:06d}"
    final, partial = os.path.join(out, name), os.path.join(out, f"{name}.partial")
    shutil.rmtree(partial, ignore_errors=True)
    os.makedirs(partial)
    t0 = time.perf_counter()
    spec = sequence_spec(cfg, index)
    stems = write_sequence(spec, cfg, index, partial)
    shutil.rmtree(final, ignore_errors=True)
    os.replace(partial, final)
    import resource
    return {"sequence": index, "folder": name, "samples": stems, "frames": len(sequence_frames(cfg, spec.n_frames)),
            "views": len(spec.views), "subjects": len(spec.subjects), "environment": spec.environment,
            "seconds": round(time.perf_counter() - t0, 3), "pid": os.getpid(),
            "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1), "rss_mb": _rss_mb()}


def _rss_mb() -> float | None:
    """The worker's resident memory now (the peak above only grows, so a leak hides in it)."""
    try:
        with open("/proc/self/statm") as fh:
            return round(int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20, 1)
    except OSError:  # not Linux
        return None


@dataclass
class Summary:
    done: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)
    seconds: float = 0.0

    def line(self) -> str:
        return (f"{len(self.done)} done, {len(self.skipped)} skipped (already complete), {len(self.failed)} failed, "
                f"{self.seconds:.1f} s")


def manifest_entries(out: str) -> dict[int, dict]:
    """Complete sequences by index (a torn last line, from a crash mid-append, is ignored)."""
    entries = {}
    path = os.path.join(out, "manifest.jsonl")
    if os.path.isfile(path):
        with open(path) as fh:
            for line in fh:
                try:
                    e = json.loads(line)
                except json.JSONDecodeError:
                    continue
                if os.path.isdir(os.path.join(out, e["folder"])):
                    entries[e["sequence"]] = e
    return entries


def _rewrite_manifest(out: str, entries: dict) -> None:
    """Keep only the complete entries (a torn last line from a crash would swallow the next
    append), written under a temporary name and renamed."""
    path = os.path.join(out, "manifest.jsonl")
    if not os.path.isfile(path):
        return
    tmp = f"{path}.tmp"
    with open(tmp, "w") as fh:
        for e in entries.values():
            fh.write(json.dumps(e, sort_keys=True) + "\n")
    os.replace(tmp, path)


def _append(out: str, entry: dict) -> None:
    timing = {k: entry[k] for k in ("seconds", "pid", "peak_rss_mb", "rss_mb")}  # the run log's, not the dataset's
    clean = {k: v for k, v in entry.items() if k not in timing}
    with open(os.path.join(out, "manifest.jsonl"), "a") as fh:
        fh.write(json.dumps(clean, sort_keys=True) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
    with open(os.path.join(out, "run.log"), "a") as fh:
        fh.write(json.dumps({"sequence": entry["sequence"], **timing, "host": socket.gethostname()}) + "\n")


def check_output(out: str) -> str:
    """The output folder, created; a clear error before any work when it cannot be written."""
    out = os.path.abspath(os.fspath(out))
    try:
        os.makedirs(out, exist_ok=True)
        probe = os.path.join(out, ".write-test")
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as exc:
        raise ConfigError("--out", out, f"cannot write there ({exc.strerror}); pick a writable folder") from None
    return out


def check_config(config: GenerateConfig) -> None:
    """Every name and file the config uses (environments, motions, a scene file), checked in
    this process before any task starts: a worker would only report it after its own setup."""
    if config.scene is not None:
        from synmitsuba.compose.scenefile import check_scene_file
        check_scene_file(config.scene, "scene")
    else:
        from synmitsuba.compose.composition import checked_sources
        checked_sources(config.compose, "compose")


RUN_FILE = "config.json"
UNCOMPARED = ("sequences", "compose.base")  # more sequences extend a dataset; a checkout's own path is not a setting


def _flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict) and v:
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def config_record(config: GenerateConfig) -> dict:
    """What ``OUT/config.json`` holds: the resolved config and the package version."""
    from synmitsuba import __version__
    return {"synmitsuba": __version__, "config": config.to_dict()}


def config_changes(old: dict, new: dict) -> list[str]:
    """``key: old -> new`` for every setting (and the version) that differs, but ``UNCOMPARED``;
    a setting the old record lacks counts only when the new one is not its default (a setting
    added since, at its default, does what the old run did)."""
    a = {"synmitsuba": old.get("synmitsuba"), **_flat(old.get("config", {}))}
    b = {"synmitsuba": new["synmitsuba"], **_flat(new["config"])}
    defaults = _flat(json.loads(json.dumps(GenerateConfig().to_dict())))
    return [f"{k}: {a.get(k)!r} -> {b.get(k)!r}" for k in sorted(set(a) | set(b))
            if k not in UNCOMPARED and a.get(k) != b.get(k) and not (k not in a and k in defaults
                                                                      and b.get(k) == defaults[k])]


def _check_run_config(out: str, config: GenerateConfig, allow_change: bool) -> None:
    """Record the config of a new dataset; refuse to add to one made with other settings (its
    sequences would silently mix them) unless ``allow_change``."""
    path, record = os.path.join(out, RUN_FILE), json.loads(json.dumps(config_record(config)))
    if not os.path.isfile(path):
        with atomic_path(path) as tmp, open(tmp, "w") as fh:
            json.dump(record, fh, indent=1, sort_keys=True)
        return
    with open(path) as fh:
        changes = config_changes(json.load(fh), record)
    if changes and not allow_change:
        shown = "; ".join(changes[:4]) + (f"; and {len(changes) - 4} more" if len(changes) > 4 else "")
        raise ConfigError("--out", out, f"holds a dataset made with other settings ({shown}); use another --out, or "
                          "--allow-config-change to add sequences made with these")
    if changes:
        with open(os.path.join(out, "run.log"), "a") as fh:
            fh.write(json.dumps({"config_changed": changes, "host": socket.gethostname()}) + "\n")


def generate(config: GenerateConfig, out: str, workers: int = 1, executor: str = "local", ray_address: str | None = None,
             max_failures: int = 2, progress: bool = True, task: Callable | None = None,
             allow_config_change: bool = False) -> Summary:
    """Render every sequence of ``config`` not yet in ``out``'s manifest; retry a failing one up to
    ``max_failures`` times, then report it (never dropped silently). Every failure's traceback
    goes to ``run.log``; ``Summary.failed`` keeps its one-line summary. ``executor`` names one
    of ``EXECUTORS``; ``task(config_dict, index, out)`` is ``run_sequence`` unless given (a
    top-level function, so spawned workers can import it)."""
    if executor not in EXECUTORS:
        raise ConfigError("--executor", executor, f"use one of {', '.join(EXECUTORS)}")
    check_config(config)
    out = check_output(out)
    _check_run_config(out, config, allow_config_change)
    for name in os.listdir(out):
        if name.endswith(".partial"):
            shutil.rmtree(os.path.join(out, name), ignore_errors=True)
    done = manifest_entries(out)
    _rewrite_manifest(out, done)
    todo = [i for i in range(config.sequences) if i not in done]
    summary = Summary(skipped=sorted(i for i in done if i < config.sequences))
    t0 = time.perf_counter()
    partial = {os.path.join(out, f"seq_{i:06d}.partial") for i in todo}
    ACTIVE_TEMPORARIES.update(partial)  # removed if the run is interrupted (after its workers are stopped)
    pool = EXECUTORS[executor](task or run_sequence, config.to_dict(), out, workers, ray_address)
    try:
        _drive(pool, todo, out, max_failures, summary, progress)
    finally:
        pool.close()
        ACTIVE_TEMPORARIES.difference_update(partial)
    summary.seconds = time.perf_counter() - t0
    return summary


def _drive(pool, todo: list, out: str, max_failures: int, summary: Summary, progress: bool) -> None:
    """Submit every sequence, then take outcomes as they come: append the complete ones, log
    and resubmit the failed ones until their tries are spent (at once for a failure that
    ``repeats``)."""
    attempts = {i: 0 for i in todo}
    images = [0]
    for i in todo:
        pool.submit(i)
    with _bar(len(todo), progress) as bar:
        for outcome in pool.as_completed():
            if outcome.failure is None:
                _finish(out, outcome.entry, summary, bar, images)
                continue
            attempts[outcome.index] += 1
            final = outcome.failure.repeats or attempts[outcome.index] > max_failures
            _log_failure(out, outcome.failure, attempts[outcome.index], final)
            if final:
                summary.failed[outcome.index] = outcome.failure.summary
            else:
                pool.submit(outcome.index)


def _log_failure(out: str, failure: Failure, attempt: int, final: bool) -> None:
    """One run.log line per failed attempt, with the whole traceback."""
    with open(os.path.join(out, "run.log"), "a") as fh:
        fh.write(json.dumps({"sequence": failure.index, "attempt": attempt, "failed": failure.summary,
                             "worker_died": failure.worker_died, "final": final, "traceback": failure.traceback,
                             "host": socket.gethostname()}) + "\n")


def _bar(total: int, progress: bool):
    from tqdm import tqdm
    return tqdm(total=total, desc="sequences", unit="seq", disable=not progress)


def _finish(out, entry, summary, bar, frames) -> None:
    _append(out, entry)
    summary.done.append(entry["sequence"])
    frames[0] += entry["frames"] * entry["views"]
    bar.set_postfix(images_per_s=f"{frames[0] / max(bar.format_dict['elapsed'], 1e-9):.2f}")
    bar.update(1)
