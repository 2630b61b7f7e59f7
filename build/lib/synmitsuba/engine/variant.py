"""Choose the Mitsuba variant once per process, safely.

``set_variant()`` picks ``cuda_ad_rgb`` when drjit finds a CUDA GPU and ``llvm_ad_rgb`` (CPU) otherwise,
both differentiable, unless told otherwise (argument or ``SYNMITSUBA_VARIANT``; ``auto`` is the
default). For LLVM variants it first makes sure a usable libLLVM is chosen: a
broken one would abort the whole process inside drjit, so we find and, if unsure, probe it.
"""
from __future__ import annotations

import os

from synmitsuba.errors import ConfigError, LLVMError
from synmitsuba.engine import llvm
from synmitsuba.process import available_cpus

DEFAULT_VARIANT = "llvm_ad_rgb"
GPU_VARIANT = "cuda_ad_rgb"
_state: dict = {"variant": None, "threads": None, "libllvm": None}


def _threads() -> int:
    env = os.environ.get("SYNMITSUBA_THREADS")
    if env:
        if not env.isdigit() or int(env) < 1:
            raise ConfigError("SYNMITSUBA_THREADS", env, "give a positive integer")
        return int(env)
    return available_cpus()


def auto_variant() -> str:
    """``cuda_ad_rgb`` when drjit can start its CUDA backend (a GPU and its driver), else
    ``llvm_ad_rgb``. Renders differ in rounding between the two; each sample records its variant."""
    import drjit as dr
    try:
        return GPU_VARIANT if dr.has_backend(dr.JitBackend.CUDA) else DEFAULT_VARIANT
    except Exception:  # a broken driver is a CPU machine to us
        return DEFAULT_VARIANT


def set_variant(name: str | None = None, threads: int | None = None) -> str:
    """Select the Mitsuba variant (default ``auto``: see ``auto_variant``) and drjit's thread count.

    Call before building scenes; calling again with the same name is free (``auto`` too). ``threads`` (default:
    the CPUs this process may use, or ``SYNMITSUBA_THREADS``) only applies before the first
    scene is loaded, as Embree fixes its builder threads then.
    """
    name = name or os.environ.get("SYNMITSUBA_VARIANT") or "auto"
    if name == "auto":
        if _state["variant"]:
            return _state["variant"]
        name = auto_variant()
    if _state["variant"] == name:
        return name
    path = _ensure_llvm() if name.startswith("llvm") else None
    import drjit as dr
    import mitsuba as mi
    if name not in mi.variants():
        raise ConfigError("variant", name, f"use auto or one of: {', '.join(mi.variants())}")
    if _state["variant"] is None:
        n = threads or _threads()
        dr.set_thread_count(n)
        _state["threads"] = n
    try:
        with llvm.libllvm_path(path):  # drjit reads it as its backend starts; the environment is restored
            mi.set_variant(name)
    except ImportError as exc:
        hint = ("it needs an NVIDIA GPU with a working driver; on a CPU use llvm_ad_rgb"
                if name.startswith("cuda") else "see `synmitsuba info`")
        raise ConfigError("variant", name, f"cannot start this variant ({exc}); {hint}") from None
    _state["variant"] = name
    return name


def _ensure_llvm() -> str | None:
    """The libLLVM for drjit (see ``llvm.choose_libllvm``), probed in a subprocess when its
    version cannot be read from its name."""
    if _state.get("llvm_ok"):
        return _state["libllvm"]
    path = llvm.choose_libllvm()  # raises LLVMError when only old ones are present
    named = path and llvm.version_from_name(os.path.realpath(path)) or (path and llvm.version_from_name(path))
    if not (named and named[0] >= llvm.MIN_VERSION):
        ok, msg = llvm.probe()
        if not ok:
            raise LLVMError(msg)
    _state["llvm_ok"], _state["libllvm"] = True, path
    return path


def current_variant() -> str | None:
    """The variant chosen in this process (None before ``set_variant``): a question, never a
    choice; ``require_variant`` is what code that needs one calls."""
    return _state["variant"]


def require_variant() -> str:
    """The chosen variant; when none was chosen yet, ``set_variant()``'s default (``auto``,
    or ``SYNMITSUBA_VARIANT``), as ``render`` and the ray casts document."""
    return _state["variant"] or set_variant()


def libllvm() -> str | None:
    """The libLLVM handed to drjit (None: drjit's own search, or a CUDA variant)."""
    return _state["libllvm"]


def thread_count() -> int | None:
    return _state["threads"]
