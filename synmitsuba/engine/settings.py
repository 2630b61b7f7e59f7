"""The names render settings accept (checked by scene files and the CLI before Mitsuba loads):
Mitsuba sampler plugins (``auto`` picks one: ``choose_sampler``) and denoisers."""
import functools

from synmitsuba.errors import ConfigError

SAMPLERS = ("auto", "ldsampler", "multijitter", "stratified", "orthogonal", "independent")
# OIDN's quality modes by denoiser name: "oidn" is OIDN's best; "balanced" and "fast" trade
# 0.4-1.5 dB of the denoised image for 2.3x / 4x less OIDN time (bench/RESULTS.md, issue 39)
OIDN_QUALITY = {"oidn": "high", "oidn-balanced": "balanced", "oidn-fast": "fast"}
DENOISERS = ("none", *OIDN_QUALITY)


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


# ``auto``'s order of preference per kind of lighting (bench/samplers.py, issue 39: under an HDRI
# multijitter beats ldsampler by 2.5 dB at 16 spp and 0.4 at 64; under a constant sky or a sun
# and sky the two are within 0.7 dB, ldsampler ahead once denoised)
AUTO_SAMPLERS = {"sky": ("ldsampler", "multijitter", "independent"),
                 "envmap": ("multijitter", "independent")}


def choose_sampler(name: str, spp: int, lighting: str = "sky") -> str:
    """The Mitsuba sampler for ``name`` (``auto``: the first of ``AUTO_SAMPLERS[lighting]`` that
    keeps ``spp`` exactly; ``lighting``: ``envmap`` for a scene lit by an HDRI, else ``sky``).
    A named sampler that would change spp is refused."""
    if name not in SAMPLERS:
        raise ConfigError("sampler", name, f"use one of {', '.join(SAMPLERS)}")
    if name == "auto":
        return next(s for s in AUTO_SAMPLERS[lighting] if s == "independent" or _keeps(s, spp))
    if not _keeps(name, spp):
        raise ConfigError("spp", spp, f"the {name} sampler cannot take {spp} samples per pixel; use sampler "
                          "'auto' or a count it takes (ldsampler: 4, 16, 64, 256, ...)")
    return name
