"""docs/cookbook.md runs as written: each recipe's grid files are saved under the names
their first line gives, its shell blocks run in a fresh folder (studyrun is STUDYRUN_BIN,
the console scripts those of the installed package, `sbatch` a stand-in that runs an
array's tasks one after the other and a `--wrap` command, as Slurm would), its Python
blocks run there against the installed package, and each prints the text block that
follows it. The README links the cookbook on its first screen and stays within 250 lines."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
COOKBOOK = REPO / "docs" / "cookbook.md"
README_LINES = 250
FIRST_SCREEN = 40

FAKE_SBATCH = '''#!{python}
"""sbatch without a cluster: `--array=A-B SCRIPT ARGS` runs SCRIPT for task A..B in turn
(SLURM_ARRAY_TASK_ID, SLURM_JOB_ID set; output to slurm-JOB_TASK.out), `--wrap CMD` runs
CMD; prints the job id as sbatch does (alone with --parsable)."""
import os, subprocess, sys

args, array, wrap, rest = sys.argv[1:], None, None, []
while args:
    a = args.pop(0)
    if a.startswith("--array="):
        array = a.split("=", 1)[1]
    elif a == "--wrap":
        wrap = args.pop(0)
    elif a.startswith("--wrap="):
        wrap = a.split("=", 1)[1]
    elif not a.startswith("--"):
        rest.append(a)
if wrap is not None:
    subprocess.run(["bash", "-c", wrap], check=True)
else:
    first, last = (int(k) for k in array.split("-"))
    for task in range(first, last + 1):
        with open(f"slurm-4242_{{task}}.out", "a") as out:
            env = {{**os.environ, "SLURM_ARRAY_TASK_ID": str(task), "SLURM_JOB_ID": "4242"}}
            subprocess.run(["bash", *rest], env=env, stdout=out, stderr=subprocess.STDOUT, check=True)
print("4242" if "--parsable" in sys.argv else "Submitted batch job 4242")
'''


def recipes():
    """{title: [(kind, text)]}: the fenced blocks of each `## ` section, in order."""
    out = {}
    for section in COOKBOOK.read_text(encoding="utf-8").split("\n## ")[1:]:
        title = section.splitlines()[0].strip()
        out[title] = re.findall(r"```(\w+)\n(.*?)```", section, flags=re.S)
    return out


def test_the_readme_links_the_cookbook_on_its_first_screen():
    lines = (REPO / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_LINES, len(lines)
    assert any("(docs/cookbook.md)" in line for line in lines[:FIRST_SCREEN])
    assert set(recipes()) == {"A labelled fault data set for a classifier", "A Sobol sensitivity study",
                              "A replicated comparison with intervals", "A Slurm array run"}


@pytest.mark.parametrize("title", sorted(recipes()))
def test_recipe_runs_as_written(title, installed, tmp_path):
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("STUDYRUN_BIN is not set")
    site, scripts = installed
    tools = tmp_path / "bin"
    tools.mkdir()
    (tools / "studyrun").symlink_to(Path(binary).resolve())
    sbatch = tools / "sbatch"
    sbatch.write_text(FAKE_SBATCH.format(python=sys.executable))
    sbatch.chmod(0o755)
    work = tmp_path / "work"
    work.mkdir()
    env = {**os.environ, "PATH": f"{tools}{os.pathsep}{scripts}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": str(site), "STUDYRUN_SRC": str(REPO), "MPLBACKEND": "Agg"}
    blocks = recipes()[title]
    assert [kind for kind, _ in blocks if kind in ("yaml", "sh", "python")], title
    printed = None
    for kind, body in blocks:
        if kind == "yaml":
            name = body.splitlines()[0].removeprefix("#").strip()
            (work / name).write_text(body)
        elif kind == "sh":
            done = subprocess.run(["bash", "-euo", "pipefail", "-c", body], cwd=work, env=env,
                                  capture_output=True, text=True)
            assert done.returncode == 0, f"{title}: {body}\n{done.stdout}\n{done.stderr}"
        elif kind == "python":
            done = subprocess.run([sys.executable, "-c", body], cwd=work, env=env, capture_output=True, text=True)
            assert done.returncode == 0, f"{title}: {body}\n{done.stderr}"
            printed = done.stdout
        elif kind == "text":
            assert printed is not None, f"{title}: a text block before any Python block"
            assert printed == body, f"{title} printed:\n{printed}"
            printed = None
    assert printed is None, f"{title}: the last Python block's output is not shown"
