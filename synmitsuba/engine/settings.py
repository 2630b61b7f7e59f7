"""The names render settings accept (checked by scene files and the CLI before Mitsuba loads):
Mitsuba sampler plugins (``auto`` picks one: ``choose_sampler``) and denoisers."""
import functools

from synmitsuba.errors import ConfigError

SAMPLERS = ("auto", "ldsampler", "multijitter", "stratified", "independent")
DENOISERS = ("none", "oidn")


@functools.lru_cache(maxsize=256)
def _keeps(sampler: str, spp: int) -> bool:
    """Whether Mitsuba's ``sampler`` takes exactly ``spp`` (asked of Mitsuba itself, with its
    rounding warning silenced: rounding is what we are probing for)."""
    import mitsuba as mi
    logger = mi.logger()  # type: ignore[operator]  # the stubs type it as an attribute
    level = logger.log_level()
    logger.set_log_level(mi.LogLevel.Error)
    try:
        return mi.load_dict({"type": sampler, "sample_count": spp}).sample_count() == spp
    finally:
        logger.set_log_level(level)


def choose_sampler(name: str, spp: int) -> str:
    """The Mitsuba sampler for ``name`` (``auto``: ldsampler, multijitter, then independent,
    the first that keeps ``spp`` exactly). A named sampler that would change spp is refused."""
    if name not in SAMPLERS:
        raise ConfigError("sampler", name, f"use one of {', '.join(SAMPLERS)}")
    if name == "auto":
        return next(s for s in ("ldsampler", "multijitter", "independent") if s == "independent" or _keeps(s, spp))
    if not _keeps(name, spp):
        raise ConfigError("spp", spp, f"the {name} sampler cannot take {spp} samples per pixel; use sampler "
                          "'auto' or a count it takes (ldsampler: 4, 16, 64, 256, ...)")
    return name
