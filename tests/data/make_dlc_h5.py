"""Make DeepLabCut HDF5 test files from the real DeepLabCut CSVs beside this script.

DeepLabCut writes its poses with pandas' `DataFrame.to_hdf`, which stores them through PyTables:
- analysed videos: `DataMachine.to_hdf(dataname, key="df_with_missing", format="table", mode="w")`
  (deeplabcut/utils/auxiliaryfunctions.py, save_data, DeepLabCut commit 5d92fdbd);
- labelled frames indexed by image path, in the table format:
  `dataFrame.to_hdf(fn + '.h5','df_with_missing',format='table', mode='w')`
  (deeplabcut/utils/conversioncode.py, convertpaths_to_unixstyle, DeepLabCut commit 7bcf276a);
- labelled frames converted from CSV: `frame.to_hdf(..., key='df_with_missing', mode='w')`, the
  default "fixed" format (same file, convertcsv2h5), with the image paths split into a row
  MultiIndex by guarantee_multiindex_rows in later versions (pandas cannot write that MultiIndex
  of rows beside MultiIndex columns in the table format).

Each CSV is read back as DeepLabCut's own readers do (`pd.read_csv(path, header=[0, 1, 2(, 3)],
index_col=0)`) and written the same way. Run from anywhere with pandas and tables installed:

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install pandas tables
    /tmp/venv/bin/python tests/data/make_dlc_h5.py

The outputs are committed: CI needs no Python.
"""

from pathlib import Path

import pandas as pd
import tables

HERE = Path(__file__).resolve().parent


def read(name, header_rows):
    return pd.read_csv(HERE / name, header=list(range(header_rows)), index_col=0)


def guarantee_multiindex_rows(df):
    """DeepLabCut's own: split image paths into a row MultiIndex of path parts."""
    if not isinstance(df.index, pd.MultiIndex):
        path = df.index[0]
        try:
            sep = "/" if "/" in path else "\\"
            df.index = pd.MultiIndex.from_tuples(tuple(df.index.str.split(sep)))
        except TypeError:
            pass


def write(df, name, **fmt):
    df.to_hdf(HERE / name, key="df_with_missing", mode="w", **fmt)


def main():
    # analyze_videos: frame-number index, table format.
    single = read("dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.csv", 3)
    write(single, "dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5", format="table")
    # Multi-animal analyze_videos: (scorer, individuals, bodyparts, coords) columns.
    multi = read("dlc_movementdata_mouse_multi_4row.csv", 4)
    write(multi, "dlc_movementdata_mouse_multi_4row.h5", format="table")
    # Labelled frames: image-path rows, table format ...
    labelled = read("dlc_labeled_CollectedData_Mackenzie.csv", 3)
    write(labelled, "dlc_labeled_CollectedData_Mackenzie.h5", format="table")
    # ... and the fixed format of convertcsv2h5, paths split into parts.
    guarantee_multiindex_rows(labelled)
    write(labelled, "dlc_labeled_CollectedData_Mackenzie_fixed.h5")
    # Not DeepLabCut's: coords (x, y, speed), for the error a reader must give.
    wrong = single.rename(columns={"likelihood": "speed"}, level="coords")
    write(wrong, "DERIVED_dlc_coords_x_y_speed.h5", format="table")
    print(f"written by pandas {pd.__version__}, PyTables {tables.__version__}")


if __name__ == "__main__":
    main()
