#!/usr/bin/env python3
"""Convert public recordings of human breathing with chest markers into the CSV of named
markers that `torso inspect` and `torso fit` read (docs/recordings.md).

The converted recordings are kept in data/real/ beside their licences; this converter
reproduces them from the published source files (data/real/README.md says where, under which
licence, and the SHA-256 of each file it was checked against). Standard library only.

Two sources:

``chestvolume``
    The 30-marker motion-capture sample of the R package ChestVolume 1.0.1 (W.-H. Kwong,
    MIT licence), ``inst/extdata/sample_data.xlsx``: one sheet, a header row ``M19 X, M19 Y,
    M19 Z, ...`` and 2309 frames of marker coordinates in millimetres, without a time column.
    The source states no frame rate, so ``--rate`` is required and written into the file as
    ``rate_assumed`` (the time column is built from it).

``extmarker``
    The external-marker sequences of Krilavicius et al. (2013/2015), as redistributed by
    M. Pohl under CC BY 4.0 (``Original data/<stamp>-<marker>-1-<tag>-<seconds>-6.csv``):
    one file per marker, ``"Frame";"Timestamp";"x";"y";"z"`` separated by ``;`` with decimal
    commas, the timestamp in milliseconds (about 10 Hz), the frame a 60 Hz counter. The
    three files of one sequence (same ``<stamp>``) are joined on their rows; a trailing row
    of zeros is dropped; a timestamp that is not increasing or disagrees with the frame
    counter by more than one 60 Hz frame stops the conversion with the file and row named
    (some sequences carry such glitches; ``--first``/``--last`` select a clean stretch).

Usage:
    python python/real_recordings.py chestvolume --xlsx sample_data.xlsx --rate 100 \
        --out data/real/chestvolume/chestvolume_sample.csv
    python python/real_recordings.py extmarker --dir "Original data" --sequence 201205101522 \
        --out data/real/extmarker/extmarker_201205101522.csv
"""

import argparse
import hashlib
import os
import re
import sys
import zipfile
import xml.etree.ElementTree as ET

SHEET_NS = {"m": "http://schemas.openxmlformats.org/spreadsheetml/2006/main"}
REL_NS = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"
AXES = ("X", "Y", "Z")


class ConversionError(Exception):
    """Bad input, with the file and the place named in the message."""


def sha256(path):
    """SHA-256 of a file, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 16), b""):
            h.update(block)
    return h.hexdigest()


def column_index(ref):
    """0-based column of a cell reference such as ``AB12``."""
    letters = re.match(r"[A-Z]+", ref)
    if not letters:
        raise ConversionError(f"cell reference `{ref}` has no column letters")
    n = 0
    for c in letters.group(0):
        n = n * 26 + (ord(c) - ord("A") + 1)
    return n - 1


def read_xlsx_first_sheet(path):
    """The first worksheet of an .xlsx file as (sheet name, rows of cell strings or None)."""
    try:
        z = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile) as e:
        raise ConversionError(f"{path}: not a readable .xlsx (zip) file: {e}") from e
    with z:
        names = set(z.namelist())
        strings = []
        if "xl/sharedStrings.xml" in names:
            for si in ET.fromstring(z.read("xl/sharedStrings.xml")).findall("m:si", SHEET_NS):
                strings.append("".join(t.text or "" for t in si.iter(f"{{{SHEET_NS['m']}}}t")))
        workbook = ET.fromstring(z.read("xl/workbook.xml"))
        sheet = workbook.find("m:sheets/m:sheet", SHEET_NS)
        if sheet is None:
            raise ConversionError(f"{path}: the workbook has no sheet")
        rid = sheet.get(f"{{{REL_NS}}}id")
        rels = ET.fromstring(z.read("xl/_rels/workbook.xml.rels"))
        target = None
        for rel in rels:
            if rel.get("Id") == rid:
                target = rel.get("Target")
        if target is None:
            raise ConversionError(f"{path}: sheet `{sheet.get('name')}` has no part")
        part = target.lstrip("/") if target.startswith("/") else "xl/" + target
        rows = []
        with z.open(part) as f:
            for _, el in ET.iterparse(f):
                if not el.tag.endswith("}row"):
                    continue
                row = []
                for c in el.findall("m:c", SHEET_NS):
                    k = column_index(c.get("r"))
                    while len(row) < k:
                        row.append(None)
                    v = c.find("m:v", SHEET_NS)
                    if v is None or v.text is None:
                        row.append(None)
                    elif c.get("t") == "s":
                        row.append(strings[int(v.text)])
                    else:
                        row.append(v.text)
                rows.append(row)
                el.clear()
        return sheet.get("name"), rows


def marker_columns(header, where):
    """Marker labels and, per marker, the column of each axis, from ``NAME X`` headers."""
    columns = {}
    for k, cell in enumerate(header):
        m = re.fullmatch(r"\s*(.+?)\s+([XYZ])\s*", cell or "")
        if not m:
            raise ConversionError(
                f"{where}: header column {k + 1} `{cell}`: expected `NAME X`, `NAME Y` or `NAME Z`"
            )
        columns.setdefault(m.group(1), {})[m.group(2)] = k
    for label, axes in columns.items():
        missing = [a for a in AXES if a not in axes]
        if missing:
            raise ConversionError(f"{where}: marker `{label}` has no {', '.join(missing)} column")
    return sorted(columns), columns


def number(text, where):
    """A coordinate cell as a float, None when empty; an error naming the cell otherwise."""
    if text is None or text.strip() == "":
        return None
    try:
        return float(text)
    except ValueError as e:
        raise ConversionError(f"{where}: `{text}` is not a number") from e


def fmt(v):
    """A coordinate as written: empty for missing, else up to 4 decimals."""
    return "" if v is None else f"{v:.4f}".rstrip("0").rstrip(".")


def write_csv(path, comments, labels, times, frames):
    """Writes a CSV of named markers: ``# key: value`` lines, header, one row per frame."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="\n") as f:
        for key, value in comments:
            f.write(f"# {key}: {value}\n")
        f.write(",".join(["time"] + [f"{l} {a}" for l in labels for a in AXES]) + "\n")
        for t, frame in zip(times, frames):
            f.write(",".join([f"{t:.4f}"] + [fmt(v) for p in frame for v in p]) + "\n")


def chestvolume(args):
    """ChestVolume's sample_data.xlsx -> CSV of named markers (mm, time from --rate)."""
    if not (args.rate > 0):
        raise ConversionError(f"--rate {args.rate}: expected a frame rate in Hz > 0")
    sheet, rows = read_xlsx_first_sheet(args.xlsx)
    if len(rows) < 2:
        raise ConversionError(f"{args.xlsx}: sheet `{sheet}` has no data rows")
    labels, cols = marker_columns(rows[0], f"{args.xlsx}: sheet `{sheet}` row 1")
    data = rows[1:]
    first = args.first
    last = len(data) if args.last is None else args.last
    if not (0 <= first < last <= len(data)):
        raise ConversionError(
            f"--first {first} --last {last}: expected 0 <= first < last <= {len(data)} frames"
        )
    frames = []
    for i in range(first, last):
        row = data[i]
        where = f"{args.xlsx}: sheet `{sheet}` row {i + 2}"
        frame = []
        for l in labels:
            frame.append(
                tuple(
                    number(row[cols[l][a]] if cols[l][a] < len(row) else None, f"{where} `{l} {a}`")
                    for a in AXES
                )
            )
        frames.append(frame)
    times = [(i - first) / args.rate for i in range(first, last)]
    comments = [
        ("units", "mm"),
        ("source", f"ChestVolume 1.0.1 inst/extdata/sample_data.xlsx, sheet {sheet}, frames {first + 1}-{last} of {len(data)}"),
        ("source_sha256", sha256(args.xlsx)),
        ("licence", "MIT (Copyright (c) 2024 Wai-Hang Kwong)"),
        ("rate_assumed", f"{args.rate:g} Hz (the source states no frame rate)"),
    ]
    write_csv(args.out, comments, labels, times, frames)
    return len(labels), len(frames)


EXT_NAME = re.compile(r"(\d{12})-([A-Z]+)-1-([A-Z]+)-(\d+)-6\.csv")


def parse_ext_file(path):
    """One ExtMarker file: rows of (frame, timestamp ms, x, y, z); trailing zero rows dropped."""
    with open(path, encoding="utf-8-sig") as f:
        lines = [l.rstrip("\r\n") for l in f]
    if not lines or [c.strip('"') for c in lines[0].split(";")] != ["Frame", "Timestamp", "x", "y", "z"]:
        raise ConversionError(f'{path}:1: expected the header "Frame";"Timestamp";"x";"y";"z"')
    rows = []
    for no, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(";")
        if len(cells) != 5:
            raise ConversionError(f"{path}:{no}: {len(cells)} cells, expected 5")
        try:
            rows.append([float(c.replace(",", ".")) for c in cells])
        except ValueError as e:
            raise ConversionError(f"{path}:{no}: `{line}` is not five numbers") from e
        rows[-1].append(no)
    while rows and all(v == 0 for v in rows[-1][:5]):
        rows.pop()
    return rows


def extmarker(args):
    """The three files of one ExtMarker sequence -> CSV of named markers (mm, s)."""
    files = {}
    for name in sorted(os.listdir(args.dir)):
        m = EXT_NAME.fullmatch(name)
        if m and m.group(1) == args.sequence:
            files[m.group(2)] = (os.path.join(args.dir, name), m.group(3))
    if len(files) != 3:
        raise ConversionError(
            f"{args.dir}: sequence {args.sequence} has {len(files)} marker files "
            f"({', '.join(sorted(files)) or 'none'}), expected 3"
        )
    labels = sorted(files)
    tables = {l: parse_ext_file(files[l][0]) for l in labels}
    n = {l: len(t) for l, t in tables.items()}
    if len(set(n.values())) != 1:
        raise ConversionError(f"sequence {args.sequence}: the files differ in length {n}")
    total = n[labels[0]]
    first = args.first
    last = total if args.last is None else args.last
    if not (0 <= first < last <= total):
        raise ConversionError(
            f"--first {first} --last {last}: expected 0 <= first < last <= {total} rows"
        )
    ref = tables[labels[0]]
    for l in labels[1:]:
        for a, b in zip(ref[first:last], tables[l][first:last]):
            if a[0] != b[0] or a[1] != b[1]:
                raise ConversionError(
                    f"{files[l][0]}:{b[5]}: frame {b[0]:g} at {b[1]:g} ms does not match "
                    f"{files[labels[0]][0]}:{a[5]} (frame {a[0]:g} at {a[1]:g} ms)"
                )
    times = []
    for k in range(first, last):
        frame, stamp, no = ref[k][0], ref[k][1], ref[k][5]
        # The frame counter runs at 60 Hz from the first row; the stamp must agree to a frame.
        expected = (frame - ref[first][0]) / 60.0 * 1000.0 + ref[first][1]
        if abs(stamp - expected) > 1000.0 / 60.0 + 1e-9 or (times and stamp / 1000.0 <= times[-1]):
            raise ConversionError(
                f"{files[labels[0]][0]}:{no}: timestamp {stamp:g} ms at frame {frame:g} is not "
                f"increasing or disagrees with the 60 Hz frame counter ({expected:.0f} ms); "
                f"choose rows with --first/--last"
            )
        times.append(stamp / 1000.0)
    t0 = times[0]
    times = [t - t0 for t in times]
    frames = [[tuple(tables[l][k][2:5]) for l in labels] for k in range(first, last)]
    tag = files[labels[0]][1]
    comments = [
        ("units", "mm"),
        ("source", f"ExtMarker sequence {args.sequence} (tag {tag}), files "
                   + ", ".join(os.path.basename(files[l][0]) for l in labels)
                   + f", rows {first + 1}-{last} of {total}"),
        ("source_sha256", " ".join(f"{l}={sha256(files[l][0])}" for l in labels)),
        ("licence", "CC BY 4.0 (Krilavicius et al. 2013; redistributed by M. Pohl)"),
    ]
    write_csv(args.out, comments, labels, times, frames)
    return len(labels), len(frames)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="source", required=True)
    c = sub.add_parser("chestvolume", help="ChestVolume sample_data.xlsx (30 markers, mm)")
    c.add_argument("--xlsx", required=True, help="inst/extdata/sample_data.xlsx of ChestVolume 1.0.1")
    c.add_argument("--rate", required=True, type=float, help="frame rate [Hz] to assume (not in the source)")
    c.add_argument("--first", type=int, default=0, help="first frame to keep (0-based)")
    c.add_argument("--last", type=int, default=None, help="one past the last frame to keep")
    c.add_argument("--out", required=True)
    e = sub.add_parser("extmarker", help="ExtMarker 'Original data' sequence (3 markers, mm, ~10 Hz)")
    e.add_argument("--dir", required=True, help='the "Original data" folder')
    e.add_argument("--sequence", required=True, help="the 12-digit stamp of the sequence, e.g. 201205101522")
    e.add_argument("--first", type=int, default=0, help="first row to keep (0-based, after the header)")
    e.add_argument("--last", type=int, default=None, help="one past the last row to keep")
    e.add_argument("--out", required=True)
    args = p.parse_args(argv)
    try:
        markers, frames = (chestvolume if args.source == "chestvolume" else extmarker)(args)
    except (ConversionError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"{args.out}: {markers} markers, {frames} frames")
    return 0


if __name__ == "__main__":
    sys.exit(main())
