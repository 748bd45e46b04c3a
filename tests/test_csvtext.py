"""The one reader of operator CSV files (issue 29, item 5: CSV parsing was written twice): data lines with
their line numbers, whatever the spreadsheet added around them."""

from __future__ import annotations

import pytest

from app.csvtext import cells, content_lines
from app.sim.stewart import PlatformError, parse_timeseries_csv


def test_data_lines_keep_their_numbers_past_a_bom_comments_blank_and_empty_spreadsheet_rows():
    text = "\ufeff# exported\n\nt,x\n ,,, \n  # note\n1,2\n,,\n3,4"
    assert content_lines(text) == ([3, 6, 8], ["t,x", "1,2", "3,4"])
    assert cells('a,"b,c", d') == ["a", "b,c", " d"]


def test_a_paced_read_gives_the_same_lines_and_calls_the_pace():
    text = "".join(f"{k},{k}\n" for k in range(40_000))  # more than one block
    calls = []
    assert content_lines(text, lambda: calls.append(1)) == content_lines(text)
    assert len(calls) >= 2


def test_every_format_reports_the_files_own_line_numbers():
    text = "\ufeff# a platform's motion\nt,x,y,z,phi,theta,psi\n,,,,,,\n0,0,0,0,0,0,0\n1,0,abc,0,0,0,0\n"
    with pytest.raises(PlatformError, match=r"m\.csv:5: column y: 'abc' is not a number"):
        parse_timeseries_csv(text, "m.csv")
    ts = parse_timeseries_csv(text.replace("abc", "0"), "m.csv")  # the empty spreadsheet row is not a sample
    assert list(ts.t) == [0.0, 1.0]


@pytest.mark.parametrize(
    ("text", "error"),
    [("abc", "not a number"), ("nan", "not a finite number"), ("-inf", "not a finite number"), ("", "not a number")],
)
def test_a_cell_that_is_no_finite_number_says_which(text, error):
    from app.csvtext import finite_number

    with pytest.raises(ValueError, match=f"^{error}$"):
        finite_number(text)
    assert finite_number(" 2.5e3 ") == 2500.0
