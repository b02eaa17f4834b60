"""The README's speed figures are measured, not remembered: its speed section cites the
benchmarks' results files kept in the repository (``benchmarks/results/*.json``, written by the
benchmarks: date, machine, commit), and every number it quotes is in the file it cites."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NUMBER = re.compile(r"(?<![A-Za-z\d.])\d+(?:\.\d+)?")  # not in a name (DOP853)


def _section(text: str, title: str) -> str:
    """The text of the ``## title`` section of a markdown page."""
    return text.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def _record_numbers(record: dict) -> set[str]:
    """Every number in a results file's quoted figures and their names, its conditions, date,
    machine and commit."""
    texts = [*record["quoted"].values(), *record["quoted"].keys(), *map(str, record["conditions"].values()),
             *record["conditions"].keys(), record["date"], record["commit"], *map(str, record["machine"].values())]
    return {n for text in texts for n in NUMBER.findall(text)}


def test_every_speed_figure_of_the_readme_is_in_the_results_it_cites():
    speed = _section((ROOT / "README.md").read_text(), "Speed")
    cited = sorted(set(re.findall(r"benchmarks/results/([a-z_]+)\.json", speed)))
    assert cited, "the speed section cites no results file"
    records = {name: json.loads((ROOT / "benchmarks" / "results" / f"{name}.json").read_text()) for name in cited}
    known = set().union(*(_record_numbers(r) for r in records.values()))
    for record in records.values():  # the section says when, where and on which code
        assert record["date"].split()[0] in speed and record["commit"].split("+")[0] in speed
    prose = re.sub(r"benchmarks/results/[a-z_]+\.json|`[^`]*`", "", speed)  # file names and code are not figures
    quoted = NUMBER.findall(prose)
    missing = [n for n in quoted if n not in known]
    assert not missing, f"README speed figures not in {', '.join(cited)}: {missing}"


@pytest.mark.parametrize("path", sorted((ROOT / "benchmarks" / "results").glob("*.json")), ids=lambda p: p.name)
def test_a_results_file_says_when_where_and_on_which_code(path):
    record = json.loads(path.read_text())
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2} \d{2}:\d{2} UTC", record["date"])
    assert record["machine"]["cpu"] and record["machine"]["cores"] >= 1 and record["machine"]["python"]
    assert re.fullmatch(r"[0-9a-f]{12}(\+dirty)?", record["commit"])
    assert (ROOT / record["benchmark"]).is_file() and record["quoted"]
