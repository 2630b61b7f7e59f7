"""Every Python snippet of the README runs as written, each on its own, saved as a file and run
from the repository root as a new user would (``python -c`` hides a missing ``__main__`` guard:
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
    script = tmp_path / f"snippet_{k}.py"
    script.write_text(SNIPPETS[k])
    r = subprocess.run([sys.executable, "-W", "error::UserWarning", str(script)], cwd=ROOT,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"snippet {k} failed:\n{SNIPPETS[k]}\n{r.stderr[-3000:]}"
