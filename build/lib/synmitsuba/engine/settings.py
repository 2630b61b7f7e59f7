"""The names render settings accept (checked by scene files and the CLI before Mitsuba loads):
Mitsuba sampler plugins (``auto`` picks one, see ``synmitsuba.rendering.denoise``) and denoisers."""
SAMPLERS = ("auto", "ldsampler", "multijitter", "stratified", "independent")
DENOISERS = ("none", "oidn")
