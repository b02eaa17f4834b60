"""The references generated from the code are current (docs/cli.md from the parsers, the
parameter tables of docs/ros.md from the nodes' tables), the docs' links lead to files of the
project, and nothing points outside it."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from biped_gait.reference_docs import CLI_PAGE, MARK, ROS_PAGE, cli_page, ros_page  # noqa: E402

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", ROOT / "msg_defs" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_the_cli_reference_is_generated_from_the_parsers():
    assert CLI_PAGE.read_text() == cli_page(), "docs/cli.md is stale: run .venv/bin/python -m biped_gait.reference_docs"


def test_the_ros_reference_has_every_parameter_from_the_nodes_tables():
    text = ROS_PAGE.read_text()
    assert [m.group(2) for m in MARK.finditer(text)] == ["biped_gait_planner", "biped_gait_simulator"]
    assert ros_page(text) == text, "docs/ros.md's parameter tables are stale: run .venv/bin/python -m biped_gait.reference_docs"


@pytest.mark.parametrize("page", PAGES, ids=[p.name if p.parent.name != "msg_defs" else "msg_defs/README.md" for p in PAGES])
def test_every_link_of_the_docs_leads_to_a_file_of_the_project(page):
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
        if "://" in target:
            continue
        assert (page.parent / target).resolve().exists(), f"{page.name}: {target}"


def test_nothing_points_outside_the_project():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    outside = [name for name in files if not name.endswith((".png", ".npz", ".gz"))
               and re.search(r"\.\./shared|/work/shared|shared/notes", (ROOT / name).read_text(errors="ignore"))
               and name != "tests/test_reference_docs.py"]
    assert not outside, outside
