"""python/real_recordings.py on small files made here in the two sources' layouts: the
values, units, times and labels written, and each malformed input refused with the file and
place named."""

import os
import sys
import zipfile

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
import real_recordings as rr  # noqa: E402


def read_written(path):
    """(comments dict, header list, rows of strings) of a converted CSV."""
    comments, rows = {}, []
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("# "):
                k, v = line[2:].split(": ", 1)
                comments[k] = v
            else:
                rows.append(line.split(","))
    return comments, rows[0], rows[1:]


def make_xlsx(path, header, data, sheet="14_902_test"):
    """A minimal .xlsx: one sheet, header as shared strings, numbers inline."""
    ns = "http://schemas.openxmlformats.org/spreadsheetml/2006/main"
    rns = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"

    def col(k):
        s = ""
        k += 1
        while k:
            k, r = divmod(k - 1, 26)
            s = chr(65 + r) + s
        return s

    rows = ['<row r="1">' + "".join(
        f'<c r="{col(k)}1" t="s"><v>{k}</v></c>' for k in range(len(header))) + "</row>"]
    for i, r in enumerate(data, start=2):
        cells = "".join(
            f'<c r="{col(k)}{i}"><v>{v}</v></c>' for k, v in enumerate(r) if v is not None)
        rows.append(f'<row r="{i}">{cells}</row>')
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("xl/workbook.xml", f'<workbook xmlns="{ns}" xmlns:r="{rns}"><sheets>'
                   f'<sheet name="{sheet}" sheetId="1" r:id="rId1"/></sheets></workbook>')
        z.writestr("xl/_rels/workbook.xml.rels",
                   '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
                   '<Relationship Id="rId1" Target="worksheets/sheet1.xml"/></Relationships>')
        z.writestr("xl/sharedStrings.xml", f'<sst xmlns="{ns}">' + "".join(
            f"<si><t>{h}</t></si>" for h in header) + "</sst>")
        z.writestr("xl/worksheets/sheet1.xml",
                   f'<worksheet xmlns="{ns}"><sheetData>{"".join(rows)}</sheetData></worksheet>')


def test_chestvolume_columns_sorted_time_from_rate_missing_kept(tmp_path):
    x = tmp_path / "s.xlsx"
    make_xlsx(x, ["M02 X", "M02 Y", "M02 Z", "M01 X", "M01 Y", "M01 Z"],
              [[1.5, 2, 3, 10, 20, 30], [1.25, 2, 3, None, 21, 31], [1, 2, 3, 12, 22, 32]])
    out = tmp_path / "o.csv"
    assert rr.main(["chestvolume", "--xlsx", str(x), "--rate", "50", "--first", "1",
                    "--out", str(out)]) == 0
    comments, header, rows = read_written(out)
    assert comments["units"] == "mm"
    assert comments["rate_assumed"].startswith("50 Hz")
    assert comments["source_sha256"] == rr.sha256(x)
    assert "frames 2-3 of 3" in comments["source"]
    assert header == ["time", "M01 X", "M01 Y", "M01 Z", "M02 X", "M02 Y", "M02 Z"]
    assert rows[0] == ["0.0000", "", "21", "31", "1.25", "2", "3"]
    assert rows[1] == ["0.0200", "12", "22", "32", "1", "2", "3"]


def test_chestvolume_refusals_name_the_place(tmp_path, capsys):
    x = tmp_path / "s.xlsx"
    make_xlsx(x, ["M01 X", "M01 Y", "speed"], [[1, 2, 3]])
    assert rr.main(["chestvolume", "--xlsx", str(x), "--rate", "100", "--out",
                    str(tmp_path / "o.csv")]) == 2
    assert "row 1: header column 3 `speed`" in capsys.readouterr().err
    make_xlsx(x, ["M01 X", "M01 Y", "M01 Z"], [[1, "two", 3]])
    with pytest.raises(rr.ConversionError, match=r"row 2 `M01 Y`: `two` is not a number"):
        rr.chestvolume(type("A", (), dict(xlsx=str(x), rate=100.0, first=0, last=None,
                                          out=str(tmp_path / "o.csv")))())
    assert rr.main(["chestvolume", "--xlsx", str(x), "--rate", "0", "--out",
                    str(tmp_path / "o.csv")]) == 2
    assert "--rate 0.0: expected a frame rate in Hz > 0" in capsys.readouterr().err
    (tmp_path / "not.xlsx").write_text("plain text")
    assert rr.main(["chestvolume", "--xlsx", str(tmp_path / "not.xlsx"), "--rate", "100",
                    "--out", str(tmp_path / "o.csv")]) == 2
    assert "not a readable .xlsx" in capsys.readouterr().err


def write_ext(folder, stamp, marker, rows, tag="N"):
    """One ExtMarker file: semicolons, decimal commas, a trailing row of zeros."""
    lines = ['"Frame";"Timestamp";"x";"y";"z"']
    for r in rows + [(0, 0, 0, 0, 0)]:
        lines.append(";".join(f"{v:g}".replace(".", ",") for v in r))
    (folder / f"{stamp}-{marker}-1-{tag}-{len(rows)}-6.csv").write_text("\n".join(lines) + "\n")


def ext_rows(n, x0, glitch_at=None):
    rows, frame, stamp = [], 0, 0.0
    for k in range(n):
        rows.append((frame, stamp if k != glitch_at else stamp / 500.0, x0 + 0.1 * k, 1.5, 60.25))
        step = 7 if k == 0 else 6
        frame += step
        stamp += round(step / 60.0 * 1000.0)
    return rows


def test_extmarker_joins_three_files_on_times(tmp_path):
    for m, x0 in (("UCC", -286.0), ("LAC", -488.0), ("UAC", -395.0)):
        write_ext(tmp_path, "201205101522", m, ext_rows(5, x0))
    write_ext(tmp_path, "201205101519", "LAC", ext_rows(5, 0.0))  # another sequence
    out = tmp_path / "o.csv"
    assert rr.main(["extmarker", "--dir", str(tmp_path), "--sequence", "201205101522",
                    "--out", str(out)]) == 0
    comments, header, rows = read_written(out)
    assert comments["units"] == "mm"
    assert "rows 1-5 of 5" in comments["source"]
    assert header[:4] == ["time", "LAC X", "LAC Y", "LAC Z"] and header[4] == "UAC X"
    assert [r[0] for r in rows] == ["0.0000", "0.1170", "0.2170", "0.3170", "0.4170"]
    assert rows[1][1:4] == ["-487.9", "1.5", "60.25"]
    assert rows[1][7] == "-285.9"


def test_extmarker_refusals_name_file_and_row(tmp_path, capsys):
    for m in ("LAC", "UAC"):
        write_ext(tmp_path, "201205101541", m, ext_rows(6, 0.0, glitch_at=3))
    args = ["extmarker", "--dir", str(tmp_path), "--sequence", "201205101541",
            "--out", str(tmp_path / "o.csv")]
    assert rr.main(args) == 2
    assert "has 2 marker files (LAC, UAC), expected 3" in capsys.readouterr().err
    write_ext(tmp_path, "201205101541", "UCC", ext_rows(6, 0.0, glitch_at=3))
    assert rr.main(args) == 2
    err = capsys.readouterr().err
    assert "201205101541-LAC-1-N-6-6.csv:5: timestamp" in err and "--first/--last" in err
    # The stretch before the glitch converts.
    assert rr.main(args + ["--last", "3"]) == 0
    (tmp_path / "201205101541-UCC-1-N-6-6.csv").unlink()
    write_ext(tmp_path, "201205101541", "UCC", ext_rows(5, 0.0))
    assert rr.main(args) == 2
    assert "the files differ in length" in capsys.readouterr().err
