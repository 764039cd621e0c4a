"""The feature table of a study file: one row per case with every per-case value the
file holds (labels, parameters, condition indicators, metrics), to CSV and Parquet.

    studyrun-features STUDY.h5 features.csv features.parquet
    python analysis/features.py STUDY.h5 features.parquet --ok

The columns are `case` (the case id) then every `[case]` variable of the file in file
order: the labels and parameters (`location`, `fault`, `defect_race`, `rpm`, …, in the
file's units), the condition indicators and band energies of an `envelope:` study
(`<channel>_kurtosis`, `<channel>_envelope_energy_bpfo`, …, docs/model.md §7.7), the
metrics (`<channel>_rms_deviation`, …), `status` and `wall_time`. Text is decoded;
numbers keep the file's dtype and NaN where a value does not apply (e.g. the defect
parameters of a healthy case). The rows are in case-id order, so a merged file and its
shards (`open_shards`) give the same table. The CSV writes NaN as `NaN` (an empty
field is an empty text). Parquet keeps each column's unit in the
table's metadata (`DataFrame.attrs["units"]` when read back with pandas).
"""

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from analysis.studyfile import open_study, study_file_or_exit, text  # noqa: E402

FORMATS = (".csv", ".parquet")
"""The suffixes of the tables `write` can write."""


def table(ds, ok_only=False):
    """The feature table of the flat study `ds` as a pandas DataFrame, one row per case
    in case-id order (`ok_only`: only the cases of status 1, ok). `attrs["units"]` maps
    each column to its unit (`1` for labels and counts)."""
    names = [str(n) for n in ds.data_vars if ds[n].dims == ("case",)]
    ds = ds[names].sortby("case")
    if ok_only and "status" in ds:
        ds = ds.isel(case=np.flatnonzero(ds["status"].values == 1))
    columns = {"case": ds["case"].values.astype(np.int64)}
    for name in names:
        values = ds[name].values
        columns[name] = np.array([text(v) for v in values], dtype=object) if values.dtype.kind in "USO" else values
    frame = pd.DataFrame(columns)
    frame.attrs["units"] = {"case": "1", **{n: str(ds[n].attrs.get("units", "1")) for n in names}}
    return frame


def write(frame, path):
    """Write the table to `path`, CSV or Parquet by its suffix (FORMATS); returns the path.
    Raises ValueError naming the path and the suffixes allowed for another suffix."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{path}: suffix {path.suffix or '(none)'} is not a table format; use one of "
                         f"{', '.join(FORMATS)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".csv":
        frame.to_csv(path, index=False, na_rep="NaN")
    else:
        frame.to_parquet(path, index=False, engine="pyarrow")
    return path


def main(argv=None):
    """Command line: see --help."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", help="study file written by studyrun (.h5)")
    parser.add_argument("out", nargs="+", help="tables to write: .csv and/or .parquet")
    parser.add_argument("--ok", action="store_true", help="only the cases that ran (status ok)")
    args = parser.parse_args(argv)
    study_file_or_exit("features", args.study)
    bad = [p for p in args.out if Path(p).suffix.lower() not in FORMATS]
    if bad:
        raise SystemExit(f"features: {bad[0]}: not a .csv or .parquet file name")
    with open_study(args.study) as ds:
        frame = table(ds.load(), args.ok)
    for path in args.out:
        print(write(frame, path))
    print(f"{len(frame)} cases, {frame.shape[1]} columns")


if __name__ == "__main__":
    main()
