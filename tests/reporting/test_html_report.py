"""``camopt report``: one self-contained HTML page, checked as text and loaded in a real
browser (Debian's headless Chromium): no console messages, every inline figure decoded,
a screenshot that is not blank."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()
BROWSERS = ("chromium", "chromium-browser", "google-chrome")
BROWSER = next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)
needs_browser = pytest.mark.skipif(
    BROWSER is None, reason="no headless Chromium on PATH (Debian: apt-get install chromium; "
    ".ci/run installs it)")
EXTERNAL = re.compile(r"""(?:src|href|action)\s*=\s*["']?\s*(?:https?:)?//""", re.I)
# after load: how many images failed to decode, written into the DOM for --dump-dom
PROBE = """<script>window.addEventListener("load", () => {
  const imgs = [...document.images];
  document.body.dataset.images = imgs.length;
  document.body.dataset.broken = imgs.filter(i => !i.complete || i.naturalWidth === 0).length;
});</script>"""


@pytest.fixture(scope="module")
def emb_report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("report")
    run = folder / "emb.h5"
    r = runner.invoke(app, ["run", str(CONFIGS / "emb.toml"), "--out", str(run), "--quiet",
                            "--set", "solver.iterations=20", "--set", "solver.particles=20",
                            "--repeats", "2"])
    assert r.exit_code == 0, r.output
    out = folder / "emb-report.html"
    r = runner.invoke(app, ["report", str(run), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert r.stdout == f"{out}\n"
    return archive.load_run(run), out


def open_in_browser(page: Path, tmp_path: Path, probe: str, window: tuple[int, int],
                    tag: str, *extra: str) -> tuple[list[str], dict[str, str], Path]:
    """Open ``page`` with ``probe`` (a script) added in headless Chromium, network blocked,
    in a ``window`` (width, height) px: its console messages, the body's data attributes
    after load, and a screenshot of the page without the probe (files named by ``tag``)."""
    probed = tmp_path / f"{tag}-{page.name}"
    probed.write_text(page.read_text().replace("</body>", probe + "</body>"))
    shot = tmp_path / f"{page.stem}-{tag}.png"
    base = [BROWSER, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            f"--user-data-dir={tmp_path / 'profile'}", "--no-first-run",
            "--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",
            *extra, f"--window-size={window[0]},{window[1]}"]
    # the browser's profile, cache and config stay in the test's folder
    env = {**os.environ, "HOME": str(tmp_path), "XDG_CONFIG_HOME": str(tmp_path / "config"),
           "XDG_CACHE_HOME": str(tmp_path / "cache")}
    dom = subprocess.run([*base, "--dump-dom", probed.as_uri()], capture_output=True,
                         text=True, timeout=120, env=env)
    assert dom.returncode == 0, dom.stderr[-2000:]
    console = [line for line in dom.stderr.splitlines() if ":CONSOLE" in line]
    body = re.search(r"<body([^>]*)>", dom.stdout)
    attrs = dict(re.findall(r'data-(\w+)="([^"]*)"', body.group(1))) if body else {}
    subprocess.run([*base, f"--screenshot={shot}", page.as_uri()], capture_output=True,
                   timeout=120, check=True, env=env)
    return console, attrs, shot


def load_in_browser(page: Path, tmp_path: Path) -> tuple[list[str], dict[str, str], Path]:
    """The page in a 1100 x 1600 window with :data:`PROBE`: console, attributes, shot."""
    return open_in_browser(page, tmp_path, PROBE, (1100, 1600), "probed",
                           "--enable-logging=stderr", "--v=0")


def not_blank(shot: Path) -> float:
    """The fraction of the screenshot's pixels that are not background white."""
    from matplotlib.image import imread

    img = imread(shot)[..., :3]
    return float(np.mean(np.any(img < 0.9, axis=-1)))


def test_report_is_one_self_contained_page(emb_report):
    view, out = emb_report
    html = out.read_text()
    assert not EXTERNAL.search(html) and "http://" not in html.replace(
        "http://www.w3.org/2000/svg", "")  # the SVG namespace is a name, never fetched
    figures = re.findall(r'<img src="data:image/svg\+xml;base64,[A-Za-z0-9+/=]+"', html)
    assert len(figures) >= 3  # convergence and the case's figures
    table = html[html.index('<table id="best-design">'):]
    table = table[:table.index("</table>")]
    for name, value in view.best.x.items():
        assert f"<td>{name}</td><td class=\"num\">{value:.6g}</td>" in table
    assert "peak_torque_nm" in table and ">reference<" in table  # beside the paper's 7.72 N m
    assert "beside the reference: paper, Sec 4.4" in html
    assert "7.72" in table
    assert f"SeedSequence({view.seed_entropy})" in html and "numpy" in html


@needs_browser
def test_report_loads_in_chromium_without_errors(emb_report, tmp_path):
    _, out = emb_report
    console, attrs, shot = load_in_browser(out, tmp_path)
    assert console == []
    assert int(attrs["images"]) >= 3 and attrs["broken"] == "0"
    assert not_blank(shot) > 0.02  # text, tables and figure lines


@needs_browser
def test_browser_check_catches_errors_and_broken_images(tmp_path):
    """The check above can fail: a console error and an image that cannot load are seen."""
    page = tmp_path / "bad.html"
    page.write_text('<html><body><p>x</p><img src="https://example.invalid/a.png">'
                    '<script>console.error("boom")</script></body></html>')
    console, attrs, shot = load_in_browser(page, tmp_path)
    assert any('"boom"' in line for line in console)
    assert attrs["broken"] == "1"
    blank = tmp_path / "blank.html"
    blank.write_text("<html><body></body></html>")
    assert not_blank(load_in_browser(blank, tmp_path)[2]) < 0.001


def test_report_of_a_sweep(tmp_path):
    out = tmp_path / "sweep.h5"
    r = runner.invoke(app, ["sweep", str(CONFIGS / "vcb.toml"), "--seeds", "0:2",
                            "--grid", "solver.population=10,20", "--set",
                            "solver.generations=10", "--set", "run.repeats=1", "--out",
                            str(out), "--quiet", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["report", str(out)])
    assert r.exit_code == 0, r.output
    html = out.with_suffix(".html").read_text()
    assert 'id="ranking"' in html and "solver.population=20" in html
    assert not EXTERNAL.search(html) and html.count('src="data:image/svg+xml') >= 1


def test_report_refuses_an_existing_file(emb_report, tmp_path):
    _, out = emb_report
    r = runner.invoke(app, ["report", str(out.with_name("emb.h5")), "--out", str(out)])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {out}: --out: ") and r.stderr.count("\n") == 1


# after load: where the verdict table ends, the window's size and the page's width
FIRST_SCREEN = """<script>window.addEventListener("load", () => {
  const t = document.getElementById("verdict-table") || document.getElementById(
    "verdict-sentence");
  const r = t.getBoundingClientRect();
  document.body.dataset.verdicttop = Math.round(r.top);
  document.body.dataset.verdictbottom = Math.round(r.bottom);
  document.body.dataset.verdictrows = t.querySelectorAll("tbody tr").length;
  document.body.dataset.atlimit = t.querySelectorAll("tbody tr.at-limit").length;
  const y = document.getElementById("expected-yield") || document.getElementById(
    "robust-yield");
  document.body.dataset.yieldbottom = y ? Math.round(y.getBoundingClientRect().bottom) : -1;
  document.body.dataset.yieldtext = y ? y.textContent : "";
  document.body.dataset.innerheight = window.innerHeight;
  document.body.dataset.innerwidth = window.innerWidth;
  document.body.dataset.scrollwidth = document.documentElement.scrollWidth;
});</script>"""
SCREEN = (1100, 800)


def first_screen(page: Path, tmp_path: Path) -> tuple[dict[str, str], Path]:
    """Open ``page`` in a 1100 x 800 headless Chromium window: the probe's attributes
    (:data:`FIRST_SCREEN`) and a screenshot of the first screen."""
    _, attrs, shot = open_in_browser(page, tmp_path, FIRST_SCREEN, SCREEN, "first-screen")
    return attrs, shot


SMALL = {  # small runs of every kind of report: (config, overrides)
    "vcb": ("vcb.toml", ["--set", "solver.generations=10", "--set", "solver.population=20",
                         "--repeats", "1"]),
    "vcb_velocity": ("vcb_velocity.toml", ["--set", "solver.generations=3", "--set",
                                           "solver.population=10", "--repeats", "1"]),
    "pareto": ("fast_switch_pareto.toml", ["--set", "solver.generations=10", "--set",
                                           "solver.population=20"]),
    "fast_switch_de": ("fast_switch_de.toml", ["--set", "solver.generations=30",
                                               "--repeats", "1"]),
}


@pytest.fixture(scope="module")
def every_report(tmp_path_factory, emb_report):
    """HTML reports of small VCB, vcb_velocity, EMB, Pareto runs and a sweep."""
    folder = tmp_path_factory.mktemp("every")
    pages = {"emb": folder / "emb.html"}  # beside its archive, as the others
    shutil.copy(emb_report[0].path, folder / "emb.h5")
    shutil.copy(emb_report[1], pages["emb"])
    for name, (config, extra) in SMALL.items():
        run = folder / f"{name}.h5"
        r = runner.invoke(app, ["run", str(CONFIGS / config), "--out", str(run), "--quiet",
                                *extra])
        assert r.exit_code == 0, r.output
        pages[name] = folder / f"{name}.html"
        r = runner.invoke(app, ["report", str(run), "--out", str(pages[name])])
        assert r.exit_code == 0, r.output
    sweep = folder / "sweep.h5"
    r = runner.invoke(app, ["sweep", str(CONFIGS / "fast_switch.toml"), "--seeds", "0:2",
                            "--set", "run.min_success_rate=0.5", "--set", "run.target=19",
                            "--out", str(sweep), "--quiet", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    pages["sweep"] = folder / "sweep.html"
    r = runner.invoke(app, ["report", str(sweep), "--out", str(pages["sweep"])])
    assert r.exit_code == 0, r.output
    return pages


@needs_browser
@pytest.mark.parametrize("name", ["vcb", "vcb_velocity", "emb", "pareto", "fast_switch_de",
                                  "sweep"])
def test_verdict_table_is_on_the_first_screen(every_report, name, tmp_path):
    """Screenshots of every kind of report: the verdict table ends inside the first
    1100 x 800 screen, the page never runs off to the right (the Pareto front's table
    included), and the screenshot shows text."""
    attrs, shot = first_screen(every_report[name], tmp_path)
    screen = int(attrs["innerheight"])  # the window less the browser's own bars
    assert 0 <= int(attrs["verdicttop"]) < int(attrs["verdictbottom"]) <= screen, attrs
    assert int(attrs["scrollwidth"]) <= int(attrs["innerwidth"]), attrs
    assert not_blank(shot) > 0.02
    html = every_report[name].read_text()
    assert re.search(r'id="verdict-sentence">(PASS|FAIL|not judged)', html)
    assert int(attrs["verdictrows"]) >= 1  # a table, not only the sentence
    if name == "sweep":
        return
    # issue #34: the expected yield and the at-limit flags are on the first screen, as
    # show --format json has them
    doc = json.loads(runner.invoke(app, ["show", str(every_report[name].with_suffix(".h5")),
                                         "--format", "json"]).stdout)
    assert 0 < int(attrs["yieldbottom"]) <= screen, attrs
    y = doc["expected_yield"]
    assert attrs["yieldtext"].startswith(f"expected yield {100 * y['value']:.1f} % "
                                         f"[{100 * y['low']:.1f}, {100 * y['high']:.1f}]")
    assert int(attrs["atlimit"]) == len(doc["at_limit"]), (attrs, doc["at_limit"])
    if name == "fast_switch_de":  # the optimum sits on the arcing limit R4 (30 deg)
        assert "initial crank angle (arcing limit)" in doc["at_limit"]
        assert int(attrs["atlimit"]) >= 1


# after load on a phone: the verdict table's pass column and the page's right edge
PHONE = """<script>window.addEventListener("load", () => {
  const d = document.body.dataset;
  const cells = [...document.querySelectorAll("#verdict-table tr > :last-child")];
  d.passright = Math.round(Math.max(...cells.map(c => c.getBoundingClientRect().right)));
  d.passleft = Math.round(Math.min(...cells.map(c => c.getBoundingClientRect().left)));
  d.passtext = cells.map(c => c.textContent.trim()).join(",");
  d.innerwidth = window.innerWidth;
  d.scrollwidth = document.documentElement.scrollWidth;
});</script>"""


@needs_browser
@pytest.mark.parametrize("name", ["vcb", "emb"])
def test_verdict_columns_fit_a_phone(every_report, name, tmp_path):
    """On a 390 x 844 phone the requirement table's pass column lies inside the screen
    for every row, and the page never runs off to the right."""
    _, attrs, shot = open_in_browser(every_report[name], tmp_path, PHONE, (390, 844), "phone")
    width = int(attrs["innerwidth"])
    assert 0 <= int(attrs["passleft"]) < int(attrs["passright"]) <= width, attrs
    assert int(attrs["scrollwidth"]) <= width, attrs
    passes = attrs["passtext"].split(",")
    assert passes[0] == "pass" and set(passes[1:]) <= {"pass", "FAIL", "at limit", "-"}, passes
    assert not_blank(shot) > 0.02


# after load: every visible table's columns reachable (the table fits the screen, or the
# box that scrolls it, itself or an ancestor with overflow-x auto/scroll, lies inside the
# screen and its scroll shows the last column), headings and captions not cut, the
# page never wider than the screen, and the charts counted
LAYOUT = """<script>window.addEventListener("load", () => {
  const d = document.body.dataset, W = window.innerWidth;
  const cut = [];
  const scrolling = el => ["auto", "scroll"].includes(getComputedStyle(el).overflowX);
  document.querySelectorAll("table").forEach((t, i) => {
    if (!t.offsetParent) return;  // hidden (a comparison not shown)
    let box = t;
    while (box && box !== document.body && !scrolling(box)) box = box.parentElement;
    if (box === document.body) box = null;
    const name = t.id || `table ${i}`;
    const rows = [...t.rows].filter(r => r.cells.length && r.offsetParent);
    const shown = c => getComputedStyle(c).display !== "none";
    const last = rows.map(r => [...r.cells].filter(shown).pop()).filter(Boolean);
    if (box) {
      const edge = Math.min(box.getBoundingClientRect().right, W);
      if (box.getBoundingClientRect().left < -1 || box.getBoundingClientRect().right > W + 1)
        cut.push(`${name}: its scrolling box runs off the screen`);
      box.scrollLeft = box.scrollWidth;  // scrolled to the end: the last column in view
      if (last.some(c => c.getBoundingClientRect().right > edge + 1))
        cut.push(`${name}: last column beyond its box when scrolled`);
      box.scrollLeft = 0;
    } else if (last.some(c => c.getBoundingClientRect().right > W + 1) ||
               t.scrollWidth > t.clientWidth + 1) {
      cut.push(`${name}: cut and no scrolling box`);
    }
  });
  document.querySelectorAll("h1, h2, h3, figcaption").forEach(h => {
    const r = h.getBoundingClientRect();
    if (h.offsetParent && (h.scrollWidth > h.clientWidth + 1 || r.right > W + 1 || r.left < -1))
      cut.push(`title cut: ${h.textContent.slice(0, 40)}`);
  });
  d.cut = cut.join(" | ");
  d.tables = document.querySelectorAll("table").length;
  d.scatters = document.querySelectorAll("svg.scatter").length;
  d.parallels = document.querySelectorAll("svg.parallel").length;
  d.points = document.querySelectorAll("svg.scatter g.point").length;
  d.lines = document.querySelectorAll("svg.parallel g.line").length;
  d.scatterright = Math.round(Math.max(0, ...[...document.querySelectorAll("svg.scatter")]
    .map(s => s.getBoundingClientRect().right)));
  d.innerwidth = W;
  d.scrollwidth = document.documentElement.scrollWidth;
});</script>"""
WINDOWS = [(1280, 900), (390, 844)]


def probe_at(page: Path, tmp_path: Path, probe: str, window: tuple[int, int], tag: str
             ) -> tuple[dict[str, str], Path]:
    """``probe``'s attributes of ``page`` laid out exactly ``window`` wide, and a
    screenshot at ``window``. Headless Chromium's --dump-dom lays a page out at least
    500 px wide whatever --window-size says, so the page is probed in an iframe of the
    window's size, its body's data attributes posted to the wrapper that is dumped."""
    post = ('<script>window.addEventListener("load", () => setTimeout(() => '
            'parent.postMessage(Object.assign({}, document.body.dataset), "*")));</script>')
    probed = tmp_path / f"{tag}-{page.name}"
    probed.write_text(page.read_text().replace("</body>", probe + post + "</body>"))
    wrapper = tmp_path / f"{tag}-frame.html"
    wrapper.write_text(
        '<!DOCTYPE html><html><body style="margin:0">'
        f'<iframe src="{probed.name}" width="{window[0]}" height="{window[1]}" '
        'style="border:0"></iframe><script>window.addEventListener("message", e => '
        'Object.assign(document.body.dataset, e.data));</script></body></html>')
    _, attrs, _ = open_in_browser(wrapper, tmp_path, "", (window[0] + 200, window[1] + 50),
                                  f"{tag}-frame", "--virtual-time-budget=5000")
    _, _, shot = open_in_browser(page, tmp_path, "", window, tag)
    return attrs, shot


def check_layout(page: Path, tmp_path: Path, window: tuple[int, int], tag: str
                 ) -> tuple[dict[str, str], Path]:
    """Open ``page`` at ``window`` with :data:`LAYOUT`: no table column or title cut, the
    page no wider than the screen, a screenshot that shows something; returns the
    probe's attributes and the screenshot (kept beside the test's files)."""
    attrs, shot = probe_at(page, tmp_path, LAYOUT, window, tag)
    assert int(attrs["innerwidth"]) == window[0], attrs
    assert attrs.get("cut") == "", attrs.get("cut")
    assert int(attrs["scrollwidth"]) <= int(attrs["innerwidth"]), attrs
    assert not_blank(shot) > 0.02
    return attrs, shot


@needs_browser
@pytest.mark.parametrize("window", WINDOWS)
@pytest.mark.parametrize("name", ["vcb", "emb"])
def test_report_tables_and_titles_whole_at_desktop_and_phone(every_report, name, window,
                                                             tmp_path):
    """The report at 1280 x 900 and 390 x 844: every table's last column reachable inside
    its scrolling box, no title cut, nothing wider than the screen (screenshots kept in
    the test's folder)."""
    attrs, shot = check_layout(every_report[name], tmp_path, window,
                               f"layout-{window[0]}x{window[1]}")
    assert int(attrs["tables"]) >= 2
    print(shot)
