"""Measured travel curves (a breaker analyser's export) and the analyser's quantities.

A curve file is CSV with a header naming a time column (``time_ms`` or ``time_s``) and a
travel column (``travel_mm`` or ``travel_m``); other columns (an analyser's further
channels) are ignored. Time runs from the close command; travel from the opened rest.
:func:`read_curve` refuses, as one :class:`~camopt.errors.ConfigError` naming the file,
what a fit could not trust: no header, a malformed row, NaN, times that do not increase,
travel in metres typed into a ``_mm`` column, a curve that never moves, and a curve longer
than :data:`MAX_SAMPLES` samples or :data:`MAX_DURATION_S`.

:func:`analyse` computes the analyser's quantities (``shared/reference/breaker-analyser.md``)
from any sampled curve, measured or simulated, the same way: closing time (command to the
touch), the average contact velocity between two calculation points on the travel, total
travel, contact wipe, over-travel and rebound. Without a contact channel the touch is
where the travel reaches the case's contact gap (``contact_gap_mm``), as the model has it.

scipy.signal is imported where used (the smoothing of a measured curve; scipy is slow to
import).
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camopt.config.loader import read_regular_file
from camopt.errors import ConfigError
from camopt.mechanics import Floats
from camopt.units import MM, MS, TO_MS

MAX_SAMPLES = 200_000
"""Samples a curve may have (an analyser records a closing at 10-20 kHz for ~0.1 s)."""
MAX_TABLE_BYTES = 64 * 2**20
"""Largest CSV file read (bytes): 200,000 rows of an analyser's export with a dozen
channels are about 30 MB; a device or a runaway log is refused before it fills memory."""
MAX_DURATION_S = 1.0
"""Longest curve (s): a VCB closes in ~50 ms; seconds typed into ``time_ms`` exceed it."""
MIN_STROKE_MM = 1.0
"""A curve that moves (well above its noise) by less than this many mm is taken as metres
in a ``_mm`` column: no breaker's drive travels less than a millimetre."""
MIN_DURATION_S = 5e-3
"""Shortest curve (s): the command, the latch delay and the stroke take tens of ms;
seconds typed into ``time_ms`` make a closing last microseconds."""
TIME_COLUMNS = {"time_ms": MS, "time_s": 1.0}
TRAVEL_COLUMNS = {"travel_mm": MM, "travel_cm": 10 * MM, "travel_m": 1.0}
VELOCITY_RANGE_M_S = (0.05, 20.0)
"""Contact velocities a breaker's closing can have (m/s): a vacuum breaker closes at
0.5-2 m/s, SF6 and air breakers up to ~10; a reading outside is a unit mix-up."""
STROKE_RANGE = (0.5, 2.0)
"""A curve's total travel must be within these multiples of its design's stroke (the
case's kinematics): a tenth is centimetres in a ``_mm`` column, a thousand times is
millimetres in a ``_m`` one."""


@dataclass(frozen=True)
class TravelCurve:
    """One measured closing: ``time`` from the close command (s, (m,), increasing) and
    ``travel`` from the opened rest (m, (m,)): the file's travel less the median of the
    samples before the motion starts (the transducer's zero). ``noise`` is the sample
    noise (m, standard deviation) estimated from second differences (robust: MAD),
    ``source`` the file it came from and ``columns`` its time and travel columns' names
    (their units)."""

    source: str
    time: Floats
    travel: Floats
    noise: float
    columns: tuple[str, str] = ("time_ms", "travel_mm")


def noise_level(y: Floats) -> float:
    """Standard deviation of white noise on a sampled travel curve, from its second
    differences d2 (var(d2) = 6 sigma^2 for white noise). Second differences remove the
    travel's straight pieces (at rest, and at 10 kHz a closing's curvature adds ~1e-6 m,
    far under a transducer's noise); a robust scale of them ignores the few kinks and
    spikes: their median absolute deviation (1.4826 MAD / sqrt(6): within 6 % on 450
    samples), unless the motion itself fills half of them, as on a coarsely sampled
    curve (at 200 Hz the MAD read 0.57 mm on 0.03 mm noise): where the MAD exceeds 1.5
    times the lower quartile's estimate (|d2|'s quartile over the half-normal's,
    0.31864 sqrt(6) sigma; within 9 % on 450 samples, 0.043 mm there), the quartile's."""
    d2 = np.diff(y, 2)
    if d2.size == 0:
        return 0.0
    dev = np.abs(d2 - np.median(d2))
    mad = 1.4826 * float(np.median(dev)) / math.sqrt(6.0)
    quartile = float(np.quantile(dev, 0.25)) / (0.31864 * math.sqrt(6.0))
    return quartile if mad > 1.5 * quartile else mad


def motion_start(travel: Floats, noise: float) -> int:
    """Index of the first sample where the curve has left its rest for good: above the
    first sample by 5 noise levels and 2 % of its stroke (0 if it starts moving)."""
    span = float(np.max(travel) - travel[0])
    above = travel - travel[0] > max(5 * noise, 0.02 * span)
    return int(np.argmax(above)) if above.any() else len(travel)


def read_table(path: str | Path, columns: Sequence[Mapping[str, float]], key: str,
               max_rows: int = MAX_SAMPLES) -> tuple[list[str], Floats]:
    """The numeric columns of a CSV file with a header: for each entry of ``columns``
    (the accepted names with their SI factors) exactly one header name; other columns
    ignored. Returns the names found and the data (rows, len(columns)) in SI. Refused as
    a ConfigError ``<file>: <where>: <what>``: a missing or unreadable file (``key``), an
    empty or headerless file, a wrong header, more than ``max_rows`` rows, a row with the
    wrong number of fields, a non-number or a non-finite value."""
    path = Path(path)
    name = str(path)
    raw = read_regular_file(path, key, MAX_TABLE_BYTES, "a CSV file")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(name, key, f"cannot read (not UTF-8 text: byte {exc.start})"
                          ) from None
    wanted = "a header naming " + " and ".join(" or ".join(c) for c in columns)
    lines = text.splitlines()
    delimiter = dialect(next((ln for ln in lines if ln.strip()), ""))
    rows = [r for r in csv.reader(lines, delimiter=delimiter) if r and any(f.strip() for f in r)]
    if not rows:
        raise ConfigError(name, "line 1", f"empty file; expected {wanted}")
    if delimiter != ",":  # ';' or tab: a decimal comma is the locale's, not a field's end
        rows = [[f.replace(",", ".") for f in r] for r in rows]
    header = [column_name(h) for h in rows[0]]
    if all(_is_number(h) for h in header):
        raise ConfigError(name, "line 1", f"no header: {wanted}")
    found = [[h for h in header if h in c] for c in columns]
    if any(len(f) != 1 for f in found):
        raise ConfigError(name, "line 1", f"columns {', '.join(header)}: need {wanted} "
                          "(one of each; an analyser's 'Time [ms]', 'Travel (mm)' read as "
                          "time_ms, travel_mm; ';' or tab separated with decimal commas)")
    names = [f[0] for f in found]
    index = [header.index(n) for n in names]
    if len(rows) - 1 > max_rows:
        raise ConfigError(name, key, f"{len(rows) - 1} samples, more than "
                          f"{max_rows}: too long a curve (crop it to the closing)")
    data = np.empty((len(rows) - 1, len(columns)))
    for k, row in enumerate(rows[1:]):
        line = k + 2
        if len(row) != len(header):
            raise ConfigError(name, f"line {line}", f"{len(row)} fields, the header has "
                              f"{len(header)}")
        for j, col in enumerate(index):
            try:
                v = float(row[col])
            except ValueError:
                raise ConfigError(name, f"line {line}", f"{header[col]}: not a number: "
                                  f"{row[col].strip()!r}") from None
            if not math.isfinite(v):
                raise ConfigError(name, f"line {line}", f"{header[col]}: {v} (every sample "
                                  "must be a finite number)")
            data[k, j] = v * columns[j][names[j]]
    return names, data


def read_curve(path: str | Path) -> TravelCurve:
    """The travel curve in a CSV file (module docstring), in SI; bad input is a
    ConfigError ``<file>: <where>: <what>``."""
    name = str(path)
    (time_name, travel_name), data = read_table(path, (TIME_COLUMNS, TRAVEL_COLUMNS),
                                                "--curve")
    if len(data) < 10:
        raise ConfigError(name, "--curve", f"{len(data)} samples: too few for a travel curve")
    time, travel = data[:, 0], data[:, 1]
    shown = time / TIME_COLUMNS[time_name]  # in the file's unit
    step = np.diff(time)
    if np.any(step <= 0):
        k = int(np.argmax(step <= 0))
        what = "repeats" if step[k] == 0 else "goes back from"
        raise ConfigError(name, f"line {k + 3}", f"{time_name} {shown[k + 1]:g} {what} "
                          f"{shown[k]:g} on the line before: times must increase")
    if time[-1] - time[0] > MAX_DURATION_S:
        hint = ("milliseconds in a _s column? name it time_ms" if time_name == "time_s"
                else "microseconds in a _ms column, or crop it to the closing")
        raise ConfigError(name, time_name, f"the curve lasts {time[-1] - time[0]:g} s, more "
                          f"than {MAX_DURATION_S:g} s: too long a curve ({hint})")
    if time[-1] - time[0] < MIN_DURATION_S:
        hint = ("seconds in a _ms column? name it time_s" if time_name == "time_ms"
                else "a closing lasts tens of ms from the command")
        raise ConfigError(name, time_name, f"the curve lasts {time[-1] - time[0]:g} s, less "
                          f"than {MIN_DURATION_S * TO_MS:g} ms: too short for a closing ({hint})")
    noise = noise_level(travel)
    start = motion_start(travel, noise)
    span = float(np.max(travel) - np.min(travel))
    if start >= len(travel) or span <= 10 * noise or np.max(travel) - travel[0] <= 10 * noise:
        raise ConfigError(name, travel_name, f"the curve never moves (it spans "
                          f"{span / TRAVEL_COLUMNS[travel_name]:g} within its noise)")
    if span < MIN_STROKE_MM * MM:
        unit = travel_name.split("_")[-1]
        moved = span / TRAVEL_COLUMNS[travel_name]
        raise ConfigError(name, travel_name, f"the travel spans {moved:g} {unit}, "
                          f"under {MIN_STROKE_MM:g} mm: "
                          + ("metres in a _mm column? name it travel_m" if unit == "mm"
                             else "not a breaker's stroke"))
    rest = float(np.median(travel[: max(start, 1)]))
    return TravelCurve(name, time, travel - rest, noise, (time_name, travel_name))


def check_scale(curve: TravelCurve, stroke: float, points: VelocityPoints) -> None:
    """Refuse a curve whose units cannot be its column names' (a ConfigError naming the
    file and column): its total travel (noise-robust: :func:`robust_peak`) outside
    :data:`STROKE_RANGE` times its design's ``stroke`` (m, the case's kinematics), or its
    contact velocity between ``points`` outside :data:`VELOCITY_RANGE_M_S`."""
    time_name, travel_name = curve.columns
    total = robust_peak(curve.travel, curve.noise, curve.time)
    ratio = total / stroke
    if not STROKE_RANGE[0] <= ratio <= STROKE_RANGE[1]:
        unit = travel_name.split("_")[-1]
        hint = {"mm": "centimetres in a _mm column? name it travel_cm" if 0.05 < ratio < 0.2
                else "metres in a _mm column? name it travel_m" if ratio < 0.05 else "",
                "m": "millimetres in a _m column? name it travel_mm" if ratio > 100 else "",
                "cm": "millimetres in a _cm column? name it travel_mm" if ratio > 5 else
                "metres in a _cm column?" if ratio < 0.05 else ""}.get(unit, "")
        raise ConfigError(curve.source, travel_name,
                          f"the curve travels {total / MM:.4g} mm, {ratio:.3g} times its "
                          f"design's stroke ({stroke / MM:.4g} mm; accepted "
                          f"{STROKE_RANGE[0]:g}-{STROKE_RANGE[1]:g} times)"
                          + (f": {hint}" if hint else ""))
    lo, hi = (first_time_at(curve.time, curve.travel, p) for p in (points.low, points.high))
    if lo is None or hi is None or hi <= lo:
        return
    v = (points.high - points.low) / (hi - lo)
    if not VELOCITY_RANGE_M_S[0] <= v <= VELOCITY_RANGE_M_S[1]:
        hint = ("seconds in a _ms column? name it time_s" if v > VELOCITY_RANGE_M_S[1]
                else "milliseconds in a _s column? name it time_ms")
        raise ConfigError(curve.source, time_name,
                          f"the contact velocity reads {v:.4g} m/s, outside a closing's "
                          f"{VELOCITY_RANGE_M_S[0]:g}-{VELOCITY_RANGE_M_S[1]:g} m/s: {hint}")


def smoothed(travel: Floats, noise: float, time: Floats) -> tuple[Floats, float]:
    """The travel smoothed for reading peaks, and the smoothed noise level (m): a
    Savitzky-Golay filter (quadratic, scipy) over ~1 ms of samples (at least 5, at most a
    quarter of the curve); the curve itself where it has no noise or too few samples. A
    raw maximum of N noisy samples reads ~sigma sqrt(2 ln N) high (3 sigma at 10 kHz); the
    filter cuts the noise to ~0.3 sigma and keeps a peak that lasts a millisecond."""
    from scipy.signal import savgol_coeffs, savgol_filter

    n = len(travel)
    dt = float(np.median(np.diff(time))) if n > 1 else 1.0
    cap = n // 4 - (1 - (n // 4) % 2)  # the largest odd number up to a quarter
    window = min(int(round(MS / dt)) | 1, cap)
    if noise <= 0 or window < 5:
        return travel, noise
    gain = float(np.sqrt(np.sum(savgol_coeffs(window, 2) ** 2)))
    return savgol_filter(travel, window, 2, mode="interp"), noise * gain


def robust_peak(travel: Floats, noise: float, time: Floats) -> float:
    """The furthest travel (m), read from the :func:`smoothed` curve."""
    return float(np.max(smoothed(travel, noise, time)[0]))


def dialect(header_line: str) -> str:
    """The field separator of a table from its header line: ``;`` (the export of a
    decimal-comma locale: its numbers' commas are decimal points) or a tab if the header
    has one, else ``,``."""
    for sep in (";", "\t"):
        if sep in header_line:
            return sep
    return ","


_UNIT = re.compile(r"(.*?)\s*(?:\[\s*([^\]]*?)\s*\]|\(\s*([^)]*?)\s*\)|/\s*(\w+))\s*")


def column_name(header: str) -> str:
    """A header field as a column name, unit in the name: an analyser's ``Time [ms]``,
    ``Travel (mm)`` or ``time/s`` reads as ``time_ms``, ``travel_mm``, ``time_s``;
    ``time_ms`` as itself (case and surrounding blanks ignored, inner blanks as ``_``)."""
    h = header.strip().lower()
    m = _UNIT.fullmatch(h)
    if m and m.group(1):
        h = f"{m.group(1)}_{next(g for g in m.groups()[1:] if g is not None)}"
    return re.sub(r"\s+", "_", h.strip())


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class VelocityPoints:
    """The two calculation points of the contact velocity, as travel (m) from the opened
    rest: the average velocity is (high - low) / (time at high - time at low), each time
    where the curve first reaches its point. Kang 2023 Sec 2.1's is the last third of the
    contact stroke: from 2/3 of the gap to the touch (:meth:`last_third`)."""

    low: float
    high: float

    @classmethod
    def last_third(cls, gap: float) -> VelocityPoints:
        """From 2/3 of the contact gap to the touch (Sec 2.1's closing velocity)."""
        return cls(2 * gap / 3, gap)


@dataclass(frozen=True)
class AnalyserQuantities:
    """A breaker analyser's quantities of one closing (SI; ``None``: not computable from
    this curve, with the reason in ``notes``). ``closing_time`` command to touch (s);
    ``contact_velocity`` between the calculation points (m/s); ``total_travel`` rest to
    the furthest point (m); ``contact_wipe`` travel beyond the touch (m, total travel
    less the gap); ``over_travel`` furthest point less the final rest (m); ``rebound``
    furthest point less the lowest point after it (m)."""

    closing_time: float | None
    contact_velocity: float | None
    total_travel: float
    contact_wipe: float | None
    over_travel: float | None
    rebound: float | None
    notes: tuple[str, ...] = ()


def first_time_at(time: Floats, travel: Floats, level: float) -> float | None:
    """Time (s) the curve first reaches ``level`` (m), linearly between samples; None if
    it never does."""
    above = travel >= level
    if not above.any():
        return None
    k = int(np.argmax(above))
    if k == 0:
        return float(time[0])
    t0, t1, s0, s1 = time[k - 1], time[k], travel[k - 1], travel[k]
    return float(t0 + (level - s0) / (s1 - s0) * (t1 - t0))


def analyse(time: Floats, travel: Floats, gap: float, points: VelocityPoints,
            rebounds: bool = True) -> AnalyserQuantities:
    """The analyser's quantities of one sampled closing, ``time`` (s) from the command
    and ``travel`` (m) from rest, (m,) each. ``rebounds`` False: the curve comes from a
    model whose closing ends at rest on the latch (no elastic stop), so over-travel and
    rebound are not computed (None, said in ``notes``). Total travel, over-travel and
    rebound of a measured curve are read from its :func:`smoothed` travel (not raw
    sample maxima), those under 3 smoothed noise levels as 0; the final rest is the
    median of the last 5 % of the samples."""
    notes: list[str] = []
    t_touch = first_time_at(time, travel, gap)
    t_low, t_high = (first_time_at(time, travel, p) for p in (points.low, points.high))
    velocity = None
    if t_low is not None and t_high is not None and t_high > t_low:
        velocity = (points.high - points.low) / (t_high - t_low)
    else:
        notes.append("the curve does not pass both velocity calculation points")
    if t_touch is None:
        notes.append("the curve never reaches the contact gap: no touch")
    smooth, floor = smoothed(travel, noise_level(travel), time) if rebounds else (travel, 0.0)
    top = int(np.argmax(smooth))
    total = float(smooth[top])
    wipe = total - gap if t_touch is not None else None
    if not rebounds:
        notes.append("over-travel and rebound: not computed by the model (its closing ends "
                     "at rest on the latch, with no elastic stop)")
        return AnalyserQuantities(t_touch, velocity, total, wipe, None, None, tuple(notes))
    tail = smooth[-max(len(travel) // 20, 1):]
    over = total - float(np.median(tail))
    rebound = total - float(np.min(smooth[top:]))
    resolved = 3 * floor  # a peak under 3 smoothed noise levels is the noise's own
    if over <= resolved or rebound <= resolved:
        notes.append(f"over-travel and rebound under {resolved / MM:.3g} mm (3 noise levels "
                     "of the smoothed curve) read as 0: the noise's, not the breaker's")
        over = 0.0 if over <= resolved else over
        rebound = 0.0 if rebound <= resolved else rebound
    return AnalyserQuantities(t_touch, velocity, total, wipe, over, rebound, tuple(notes))
