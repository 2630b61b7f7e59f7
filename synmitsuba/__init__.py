"""synmitsuba: synthetic, exactly annotated datasets of people rendered with Mitsuba 3."""
__version__ = "0.1.0"
