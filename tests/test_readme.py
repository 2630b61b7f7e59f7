"""Every Python snippet of the README runs as written, each on its own in a fresh interpreter
(from the repository root, as a new user would paste it)."""
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
def test_readme_snippet_runs_alone(k):
    r = subprocess.run([sys.executable, "-W", "error::UserWarning", "-c", SNIPPETS[k]], cwd=ROOT,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"snippet {k} failed:\n{SNIPPETS[k]}\n{r.stderr[-3000:]}"
