"""Every Python snippet of the README runs as written, each on its own, saved as a file and run
from a bare repository root as a new user would (``python -c`` hides a missing ``__main__`` guard:
spawned workers import the main module again)."""
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SNIPPETS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)


def test_the_readme_has_snippets():
    assert len(SNIPPETS) >= 3


@pytest.mark.parametrize("k", range(len(SNIPPETS)))
def test_readme_snippet_runs_alone(k, tmp_path):
    """Run where a new user's checkout has nothing written yet: a folder linking the checkout's
    configs/ and scenes/, so each snippet makes its out/ from nothing (run in the checkout
    itself, the generation snippets found the last run's out/tiny complete and skipped it)."""
    root = tmp_path / "checkout"
    root.mkdir()
    for name in ("configs", "scenes"):
        (root / name).symlink_to(ROOT / name)
    script = tmp_path / f"snippet_{k}.py"
    script.write_text(SNIPPETS[k])
    r = subprocess.run([sys.executable, "-W", "error::UserWarning", str(script)], cwd=root,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"snippet {k} failed:\n{SNIPPETS[k]}\n{r.stderr[-3000:]}"
