"""A sweep's files: ``sweep.csv`` (one row a gait, written as chains finish and flushed, so an
interrupted sweep keeps its rows) and ``sweep.json`` (the grid and every gait, written when
the sweep ends or is interrupted, with ``complete`` saying which).

Every figure of ``views.to_dict(gait, trajectory=False)`` (``core.gait.views.FIELDS``) is kept, SI with radians, plus
``arm_amplitude_deg`` for reading; in the CSV, list values are JSON text and NaN is empty.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path
from types import TracebackType

from ..core.gait import views
from ..core.gait.gait import Gait
from ..core.gait.views import FIELDS
from .sweep import SweepGrid

CSV_NAME = "sweep.csv"
JSON_NAME = "sweep.json"
OUTPUT_PATTERNS = (CSV_NAME, JSON_NAME, JSON_NAME + ".part", "W_vs_*.png")  # what a sweep writes


def remove_previous(out_dir: Path) -> list[Path]:
    """Delete the files an earlier sweep wrote in ``out_dir`` (nothing else); returns them."""
    removed = sorted({p for pattern in OUTPUT_PATTERNS for p in Path(out_dir).glob(pattern) if p.is_file()})
    for path in removed:
        path.unlink()
    return removed


def csv_columns() -> list[str]:
    """Column names: the result's fields in order (no trajectory), ``arm_amplitude_deg`` after alpha."""
    names = [f.key for f in FIELDS if f.key != "trajectory"]
    at = names.index("arm_amplitude") + 1
    return names[:at] + ["arm_amplitude_deg"] + names[at:]


def case_record(result: Gait) -> dict:
    """A gait as a JSON-ready dict with ``arm_amplitude_deg`` added."""
    record = views.to_dict(result, trajectory=False)
    record["arm_amplitude_deg"] = round(math.degrees(result.arm_amplitude), 9)
    return record


def _cell(value: object) -> object:
    return json.dumps(value) if isinstance(value, list) else ("" if value is None else value)


def _csv_text(results: list[Gait] | None) -> str:
    """CSV lines of ``results``, or the header line for None; composed in memory so that a
    chain reaches the file in one write (an interrupt cannot leave half a chain)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=csv_columns())
    if results is None:
        writer.writeheader()
    for result in results or ():
        writer.writerow({k: _cell(v) for k, v in case_record(result).items()})
    return buffer.getvalue()


class SweepFiles:
    """Writes the files of one sweep into ``out_dir`` (created if missing); a context manager.

    ``add`` appends a finished chain's rows to the CSV at once; leaving the ``with`` block
    writes the JSON, and after a complete sweep rewrites the CSV in grid order.
    """

    def __init__(self, out_dir: Path, grid: SweepGrid):
        self.out_dir = Path(out_dir)
        self.grid = grid
        self.chains: dict[int, list[Gait]] = {}
        self._file = None

    @property
    def csv_path(self) -> Path:
        return self.out_dir / CSV_NAME

    @property
    def json_path(self) -> Path:
        return self.out_dir / JSON_NAME

    @property
    def count(self) -> int:
        """Gaits written so far."""
        return sum(len(rows) for rows in self.chains.values())

    @property
    def complete(self) -> bool:
        return self.count == self.grid.size

    def results(self) -> list[Gait]:
        """The gaits received so far, in grid order."""
        return [r for index in sorted(self.chains) for r in self.chains[index]]

    def __enter__(self) -> "SweepFiles":
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self._file = self.csv_path.open("w", newline="")
        self._file.write(_csv_text(None))
        self._file.flush()
        return self

    def add(self, index: int, results: list[Gait]) -> None:
        """Append chain ``index``'s gaits to the CSV (one write, flushed) and record them."""
        self._file.write(_csv_text(results))
        self._file.flush()
        self.chains[index] = results

    def document(self) -> dict:
        """The sweep as JSON-ready values: whether it is complete, its grid, every gait so far."""
        return {
            "complete": self.complete,
            "cases_planned": self.grid.size,
            "cases_written": self.count,
            "grid": self.grid.describe(),
            "cases": [case_record(r) for r in self.results()],
        }

    def __exit__(self, exc_type: type | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self._file.close()
        if self.complete:
            self.csv_path.write_text(_csv_text(None) + _csv_text(self.results()), newline="")
        partial = self.json_path.with_suffix(".json.part")
        partial.write_text(json.dumps(views.clean(self.document()), indent=1))
        os.replace(partial, self.json_path)
