"""Output files of a report run: every file is written to a temporary name in its folder and
renamed, so an interrupted run never leaves a half-written report, CSV or image."""

from __future__ import annotations

import csv
import io
import json
import os
from typing import Callable, Collection, Dict, Iterable, List

from .. import atomic_write
from ..json_values import strict_json


def write_bytes(path: str, data: bytes) -> None:
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    atomic_write.write_bytes(path, data)


def write_text(path: str, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))


def write_json(path: str, value) -> None:
    write_text(path, json.dumps(strict_json(value), indent=2, allow_nan=False) + "\n")


def write_csv(path: str, rows: Iterable[Dict[str, object]]) -> None:
    """Rows as CSV; the columns are the union of the rows' keys in first-seen order; lists are
    joined with spaces, dicts written as JSON, missing or non-finite values are empty."""
    rows = list(rows)
    columns: List[str] = []
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        cells = []
        for key in columns:
            value = strict_json(row.get(key))
            if value is None:
                cells.append("")
            elif isinstance(value, list):
                cells.append(" ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in value))
            elif isinstance(value, dict):
                cells.append(json.dumps(value, sort_keys=True))
            elif isinstance(value, float):
                cells.append(f"{value:.6g}")
            else:
                cells.append(str(value))
        writer.writerow(cells)
    write_text(path, out.getvalue())


def remove_unwritten(folder: str, written: Collection[str], owned: Callable[[str], bool]) -> List[str]:
    """Deletes the files of `folder` a run owns (`owned(name)`) but did not write this time (a
    table of a section the preset skipped, an image of a view an earlier run had), so that the
    folder shows this run alone; files the report never writes are left. Returns the names
    removed, sorted."""
    removed = []
    for name in sorted(os.listdir(folder)):
        if owned(name) and name not in written and os.path.isfile(os.path.join(folder, name)):
            os.remove(os.path.join(folder, name))
            removed.append(name)
    return removed
