"""Tables (lists of row dicts) as one HDF5 dataset per column."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence

import h5py
import numpy as np

from camopt.core.documents import Cell, Row

STR = h5py.string_dtype()


def write_table(group: h5py.Group, rows: Sequence[Mapping[str, Cell]]) -> None:
    """Rows as one dataset per column: booleans as bool, whole numbers as int64, other
    numbers as float64, lists and strings as JSON text per row."""
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    group.attrs["columns"] = json.dumps(columns)
    for col in columns:
        values = [row.get(col) for row in rows]
        if all(isinstance(v, (bool, np.bool_)) for v in values):
            group.create_dataset(col, data=np.array(values, dtype=bool))
        elif all(isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))
                 for v in values):
            group.create_dataset(col, data=np.array(values, dtype=np.int64))
        elif all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                 for v in values):
            group.create_dataset(col, data=np.array(values, dtype=float))
        else:  # lists and strings: JSON text per row
            group.create_dataset(col, data=[json.dumps(v) for v in values], dtype=STR)
            group[col].attrs["json"] = True


def read_table(group: h5py.Group) -> list[Row]:
    """Rows written by :func:`write_table`."""
    columns = json.loads(group.attrs["columns"])
    data = {}
    for col in columns:
        ds = group[col]
        if ds.attrs.get("json", False):
            data[col] = [json.loads(v) for v in ds.asstr()[()]]
        else:
            data[col] = ds[()].tolist()
    n = len(data[columns[0]]) if columns else 0
    return [{c: data[c][i] for c in columns} for i in range(n)]
