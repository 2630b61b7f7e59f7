"""Errors raised for bad input. Messages name the field, the value and the fix."""


class SynMitsubaError(Exception):
    """Base class of every error synmitsuba raises on purpose."""


class ConfigError(SynMitsubaError, ValueError):
    """A field of a config, recipe, scene file or argument has a bad value."""

    def __init__(self, field: str, value, fix: str):
        self.field, self.value, self.fix = field, value, fix
        super().__init__(f"{field} = {value!r}: {fix}")


class LLVMError(SynMitsubaError, RuntimeError):
    """drjit's LLVM backend cannot run with the libLLVM on this machine."""


class SynMitsubaWarning(UserWarning):
    """Something that renders but is probably not what was meant (a view that sees nothing,
    a scene without light)."""
