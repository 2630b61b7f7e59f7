"""colour-science, imported without its warning that matplotlib (used only for plots) is missing."""
import warnings


def import_colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    return colour
