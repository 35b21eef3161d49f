"""``camopt dashboard``: one offline page over a folder of archives, loaded in headless
Chromium (network blocked): it lists every archive with its verdict, sorts on a click,
filters, and two ticked runs show only the values that differ."""

from __future__ import annotations

import shutil
from urllib.parse import unquote, urlsplit

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from camopt.cli import app
from camopt.reporting.dashboard import relative_href, render
from tests.conftest import CONFIGS
from tests.reporting.test_html_report import (
    EXTERNAL,
    WINDOWS,
    check_layout,
    needs_browser,
    open_in_browser,
)

runner = CliRunner()
# the shipped configs, with small budgets (the page, not the optimum, is under test)
RUNS = {"vcb": ("vcb.toml", ["run.repeats=1", "solver.generations=8"]),
        "vcb_velocity": ("vcb_velocity.toml", ["run.repeats=1", "solver.generations=8"]),
        "fast_switch": ("fast_switch.toml", []),
        "emb": ("emb.toml", ["solver.iterations=10", "solver.particles=10", "run.repeats=1"]),
        "opening_spring": ("opening_spring_pp3.toml", [])}
# after load: sort by objective (twice: descending), filter, tick two vcb runs
PROBE = """<script>window.addEventListener("load", () => {
  const d = document.body.dataset;
  const names = () => [...document.querySelectorAll("#runs tbody tr:not(.hidden) td.name")]
    .map(td => td.textContent.trim().split(" ")[0]);
  d.total = names().length;
  d.verdicts = [...document.querySelectorAll("#runs tbody tr td:nth-child(4)")]
    .map(td => td.textContent).join(",");
  const objectives = () => [...document.querySelectorAll("#runs tbody tr td:nth-child(6)")]
    .map(td => td.textContent.trim().split(" ")[0]);
  const th = document.querySelector('#runs th[data-key="objective"]');
  th.click(); d.ascending = objectives().join(",");
  th.click(); d.descending = objectives().join(",");
  const f = document.getElementById("filter");
  f.value = "vcb"; f.dispatchEvent(new Event("input"));
  d.filtered = names().join(",");
  const picks = [...document.querySelectorAll("#runs tbody tr:not(.hidden) .pick")];
  for (const p of picks.slice(0, 2)) { p.checked = true; p.dispatchEvent(new Event("change")); }
  d.compare = document.getElementById("compare-title").textContent;
  d.hidden = document.getElementById("compare").hidden;
  d.diff = [...document.querySelectorAll("#diff tbody tr td:first-child")]
    .map(td => td.textContent).join(",");
  const same = [...document.querySelectorAll("#diff tbody tr")]
    .filter(tr => tr.cells[1].textContent === tr.cells[2].textContent).length;
  d.same = same;
});</script>"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    runs = tmp_path_factory.mktemp("runs")
    for name, (file, overrides) in RUNS.items():
        sets = [a for o in overrides for a in ("--set", o)]
        r = runner.invoke(app, ["run", str(CONFIGS / file), "--out", str(runs / f"{name}.h5"),
                                "--quiet", *sets])
        assert r.exit_code == 0, r.output
    assert runner.invoke(app, ["report", str(runs / "fast_switch.h5")]).exit_code == 0
    (runs / "notes.h5").write_text("not an archive")  # listed, never fatal
    r = runner.invoke(app, ["dashboard", str(runs)])
    assert r.exit_code == 0, r.output
    assert r.stdout == f"{runs / 'index.html'}\n"
    return runs


def test_page_is_self_contained_and_links_reports(folder):
    page = (folder / "index.html").read_text()
    assert not EXTERNAL.search(page)
    assert '<a href="./fast_switch.html">fast_switch.h5</a>' in page
    assert "<script src" not in page and "<link" not in page
    r = runner.invoke(app, ["dashboard", str(folder)])  # never over a page without --force
    assert r.exit_code == 2 and r.stderr.startswith("error: ")
    assert runner.invoke(app, ["dashboard", str(folder), "--force"]).exit_code == 0


@needs_browser
@pytest.mark.parametrize("window", [(1280, 900), (390, 844)])
def test_dashboard_sorts_filters_and_compares_in_chromium(folder, tmp_path, window):
    console, d, shot = open_in_browser(folder / "index.html", tmp_path, PROBE, window,
                                       f"probed-{window[0]}", "--enable-logging=stderr",
                                       "--v=0")
    assert not [c for c in console if "Uncaught" in c or "Error" in c], console
    assert int(d["total"]) == len(RUNS) + 1
    verdicts = d["verdicts"].split(",")
    assert set(verdicts[:-1]) <= {"PASS at nominal", "FAIL"}, verdicts  # the vocabulary
    assert verdicts[-1].startswith("file: not a camopt archive")
    assert "FAIL" in verdicts
    for order, direction in (("ascending", 1), ("descending", -1)):
        cells = d[order].split(",")
        shown = [float(c) for c in cells if c != "-"]
        assert len(shown) == len(RUNS) and cells[len(shown):] == ["-"]  # missing last
        assert shown == sorted(shown, reverse=direction < 0)
    assert d["filtered"].split(",") == ["vcb_velocity.h5", "vcb.h5"]
    assert d["hidden"] == "false"
    assert d["compare"].startswith("vcb_velocity.h5 vs vcb.h5: ")
    diff = d["diff"].split(",")
    # only what differs: the config's changes between the two files are there, no equal row
    assert "config.run.name" in diff and int(d["same"]) == 0
    assert any(k.startswith("result.") for k in diff)
    assert shot.stat().st_size > 5000
    keep = shutil.copy(shot, tmp_path / f"dashboard-{window[0]}x{window[1]}.png")
    print(keep)


@needs_browser
@pytest.mark.parametrize("window", WINDOWS)
def test_dashboard_charts_and_tables_fit_desktop_and_phone(folder, tmp_path, window):
    """The dashboard at 1280 x 900 and 390 x 844 with its charts: a scatter and a
    parallel-coordinates view per case, a point per run with an objective and an expected
    yield, a line per run; no table column or title cut; the scatter inside the screen.
    The dashboard's table is wider than a phone: its box scrolls (the probe scrolls it
    to the last column)."""
    from camopt.reporting.dashboard import rows

    found = [r for r in rows(folder) if r.archive == "run" and r.objective_name]
    attrs, shot = check_layout(folder / "index.html", tmp_path, window,
                               f"dashboard-{window[0]}x{window[1]}")
    cases = {r.case for r in found}
    assert int(attrs["scatters"]) == int(attrs["parallels"]) == len(cases)
    assert int(attrs["points"]) == sum(r.objective is not None and r.expected_yield
                                       is not None for r in found)
    assert int(attrs["lines"]) == len(found)
    assert 0 < int(attrs["scatterright"]) <= int(attrs["innerwidth"]), attrs
    print(shot)


def _rows(yields, objectives):
    from camopt.reporting.dashboard import DashboardRow

    return [DashboardRow(name=f"r{i}.h5", archive="run", case="c", solver="s",
                         verdict="pass" if i % 2 else "fail", expected_yield=y,
                         objective_name="torque_nm", objective=o, created="", seed=0,
                         report=None, design={"x_mm": float(i)})
            for i, (y, o) in enumerate(zip(yields, objectives))]


def test_scatter_places_points_on_its_axes():
    """A point's x is its yield on the drawn yield axis (the 0 %, 50 % and 100 % ticks
    at the points of yield 0, 0.5 and 1, within 0.1 px), a larger objective higher; a
    run without a yield is left out and said so."""
    import re

    from camopt.reporting.dashboard import parallel, scatter

    chart = scatter("c", _rows([0.0, 0.5, 1.0, None], [3.0, 1.0, 2.0, 5.0]))
    cx = [float(v) for v in re.findall(r'<circle cx="([\d.]+)"', chart.svg)]
    cy = [float(v) for v in re.findall(r'<circle cx="[\d.]+" cy="([\d.]+)"', chart.svg)]
    ticks = {label: float(x) for x, label in
             re.findall(r'<text x="([\d.]+)" y="[\d.]+" text-anchor="middle" '
                        r'font-size="11">(\d+) %</text>', chart.svg)}
    assert len(cx) == 3 and "1 run" in chart.note
    assert [cx[0], cx[1], cx[2]] == pytest.approx([ticks["0"], ticks["50"], ticks["100"]],
                                                  abs=0.1)
    assert cy[0] < cy[2] < cy[1]  # SVG y grows downwards: objective 3 highest
    lines = parallel("c", _rows([0.2, 0.9], [1.0, 2.0]))
    assert lines.svg.count('class="line"') == 2 and "x_mm" in lines.svg


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.text(min_size=1, max_size=40).filter(lambda n: "/" not in n and "\0" not in n)
       | st.sampled_from(["javascript:alert(1);({}).html", "JaVaScRiPt:x.html",
                          "data:text/html,<script>x</script>.html", "//evil.example/x.html",
                          "#top.html", "?q=1.html", "%2e%2e.html", " javascript:x.html",
                          "\tjavascript:x.html", "vbscript:x.html"]))
def test_a_report_link_is_always_the_file_beside_the_page(name):
    """Whatever the archive's name, its href parses (RFC 3986, as a browser does) as a
    path relative to the page with no scheme, host, query or fragment, and decodes back
    to the name: a name such as 'javascript:...' cannot become a script link."""
    href = relative_href(name)
    parts = urlsplit(href)
    assert (parts.scheme, parts.netloc, parts.query, parts.fragment) == ("", "", "", "")
    assert parts.path.startswith("./") and unquote(parts.path[2:]) == name
    assert href.isascii() and not any(c in href for c in "\"<>' \t\n")


def test_an_archive_named_like_a_script_url_links_as_a_file(folder, tmp_path):
    """The hostile run of issue #49: an archive named 'javascript:...;({}).h5' with its
    report beside it gave href="javascript:...": a script link."""
    name = "javascript:document.title='pwned';({})"
    shutil.copy(folder / "fast_switch.h5", tmp_path / f"{name}.h5")
    (tmp_path / f"{name}.html").write_text("<p>report</p>")
    page = render(tmp_path)
    assert 'href="./javascript%3Adocument.title%3D%27pwned%27%3B%28%7B%7D%29.html"' in page
    assert 'href="javascript' not in page.lower()
