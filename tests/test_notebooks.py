"""The notebooks run end to end (tiny settings in their ``parameters`` cell) and are stored
with their outputs stripped. The dataset notebooks read the suite's shared tiny dataset
(``ROOT``) instead of generating their own: generation is tested on its own."""
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NOTEBOOKS = os.path.join(ROOT, "notebooks")
TINY = {"01_quickstart": "SIZE = 48\nSPP = 2\nTEXTURE = 64",
        "02_texture_fitting": "SIZE = 24\nSTEPS = 3\nSPP = 2\nTARGET_SPP = 4",
        "03_dataset": "ROOT = {tiny!r}\nCONFIG = '../configs/tiny.yaml'",
        "04_training": "ROOT = {tiny!r}\nCONFIG = '../configs/tiny.yaml'\nSTEPS = 20\nSIZE = 64"}


def _read(name):
    nbformat = pytest.importorskip("nbformat")
    return nbformat.read(os.path.join(NOTEBOOKS, f"{name}.ipynb"), as_version=4)


@pytest.mark.parametrize("name", sorted(TINY))
def test_notebook_is_stored_without_outputs(name):
    for cell in _read(name).cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, name


@pytest.mark.parametrize("name", sorted(TINY))
def test_notebook_runs(name, request):
    nbclient = pytest.importorskip("nbclient")
    nb = _read(name)
    params = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
    assert len(params) == 1
    params[0].source = TINY[name]
    if "{tiny!r}" in params[0].source:
        params[0].source = params[0].source.format(tiny=str(request.getfixturevalue("tiny")))
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": NOTEBOOKS}}).execute()
    images = sum(o.get("output_type") == "display_data" and "image/png" in o.get("data", {})
                 for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert images >= 2, name  # the plots were drawn
