"""Tables (the global series, events, precursors, sweep outcomes) as pandas
DataFrames when pandas is installed, else as numpy structured arrays. Both
answer ``table["column"]`` with an array-like and ``len(table)``."""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

_kind = "auto"


def set_tables(kind: str) -> None:
    """Choose what tables are: ``"pandas"`` (DataFrames), ``"numpy"``
    (structured arrays) or ``"auto"`` (pandas when it is installed)."""
    global _kind
    if kind not in ("auto", "pandas", "numpy"):
        raise ValueError(f"tables = {kind!r}: expected 'auto', 'pandas' or 'numpy'")
    if kind == "pandas":
        import pandas  # noqa: F401  (fails here, not at the first table)
    _kind = kind


def _pandas():
    if _kind == "numpy":
        return None
    try:
        import pandas
    except ImportError:
        if _kind == "pandas":
            raise
        return None
    return pandas


def structured(columns: Mapping[str, Sequence[Any]]) -> np.ndarray:
    """The columns as one numpy structured array (strings as str fields)."""
    arrays = {name: np.asarray(values) for name, values in columns.items()}
    lengths = {len(a) for a in arrays.values()}
    if len(lengths) > 1:
        raise ValueError(f"columns of different lengths: {sorted(lengths)}")
    n = lengths.pop() if lengths else 0
    dtype = []
    for name, a in arrays.items():
        if a.dtype.kind in "OU":
            width = max((len(str(v)) for v in a), default=1)
            dtype.append((name, f"U{max(width, 1)}"))
        else:
            dtype.append((name, a.dtype))
    out = np.empty(n, dtype=dtype)
    for name, a in arrays.items():
        out[name] = a
    return out


def table(columns: Mapping[str, Sequence[Any]]):
    """A DataFrame or a structured array of the columns (see `set_tables`)."""
    pandas = _pandas()
    if pandas is None:
        return structured(columns)
    return pandas.DataFrame({name: np.asarray(v) for name, v in columns.items()})


def read_csv(path: str):
    """A CSV table (a sweep's ``summary.csv``): numbers as numbers (blank:
    NaN), other columns as text."""
    pandas = _pandas()
    if pandas is not None:
        return pandas.read_csv(path, keep_default_na=True)
    import csv

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    columns: dict[str, Sequence[Any]] = {}
    for k, name in enumerate(header):
        raw = [r[k] if k < len(r) else "" for r in body]
        columns[name] = _typed(raw)
    return structured(columns)


def _typed(raw: list[str]) -> np.ndarray:
    try:
        if all(v != "" for v in raw):
            return np.array([int(v) for v in raw], dtype=np.int64)
    except ValueError:
        pass
    try:
        return np.array([float(v) if v != "" else np.nan for v in raw], dtype=np.float64)
    except ValueError:
        return np.array(raw, dtype=str)
