"""Placing a camera take in the time of the pattern sequence it filmed (docs/capture.md, *The take*).

Camera and player are not synchronised (another rate, a late start, blended, dropped or repeated
frames, flicker) and the wall's colours are not known yet, so the take is placed by the
sequence's **sync marks** (:mod:`ocio_vp.patterns.design`): white flashes, told apart by number.

1. **Brightness** per frame: ``min_c (x_c - lo_c) / (hi_c - lo_c)``, ``lo``/``hi`` each channel's
   2nd/99.5th percentiles over the take: ~1 for a flash, low for black, a primary or a ramp.
2. **Runs** of bright frames by hysteresis, each edge timed where the brightness crosses
   half-way, interpolated between two frames (blended frames make this sub-frame).
3. **Marks**: chains of runs of similar length and gaps; ``k`` flashes are mark ``k - 2``. Runs
   cut by the take's first or last frame are left out.
4. **Rate and offset** of ``t = offset + rate * T`` (camera against player frames): of the lines
   through pairs of marks, the one most marks agree with, refitted on them all.
5. **Anchors**: every mark, and every patch change whose colours differ well above the frames'
   scatter, timed where the frames cross half-way; the map interpolates the anchors' offsets,
   so a dropped (or repeated) frame is a step in it, found and reported.
6. **Frames kept** per patch: inside it, :data:`GUARD` camera frames from both changes.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.patterns.sequence import Patch, PatternSequence

__all__ = [
    "GUARD",
    "Alignment",
    "Run",
    "align_take",
    "bright_runs",
    "brightness",
    "kept_frames",
]

#: Camera frames left out next to each patch change.
GUARD = 2.0
_HIGH, _LOW, _MID = 0.6, 0.4, 0.5
#: Largest residual (camera frames) of a mark's edges against the fitted line.
MARK_TOLERANCE = 0.6
#: A patch change's time may differ from its neighbours' by this much (camera frames): with a
#: short shutter a change is a sharp step between two frames, timed only to about half a frame.
ANCHOR_TOLERANCE = 0.75
#: Most frames dropped (or repeated) between two sync marks that still places them.
MAX_STEP = 3
#: A change of the anchors' offset by more than this (camera frames) is a dropped or
#: repeated frame.
STEP_THRESHOLD = 0.7
#: A patch change is an anchor when its colour step exceeds this many times the frames' scatter.
CHANGE_SIGMAS = 5.0
#: ...and this fraction of the brighter side.
CHANGE_RELATIVE = 0.05


@dataclass(frozen=True)
class Run:
    """Bright frames ``first``..``last`` (indices), edges ``rise``/``fall`` in frame times."""

    first: int
    last: int
    rise: float
    fall: float

    @property
    def length(self) -> float:
        return self.fall - self.rise


@dataclass(frozen=True)
class Alignment:
    """Where the sequence lies in the take: ``to_camera(T)`` maps player frames to camera
    frame times (frame numbers). ``anchors`` are (player time, camera time) pairs the map goes
    through; ``steps`` the dropped (negative) or repeated (positive) camera frames found, as
    (player frame, camera frames)."""

    rate: float
    offset: float
    anchor_times: np.ndarray
    anchor_offsets: np.ndarray
    marks_found: tuple[int, ...]
    marks_expected: int
    changes_used: int
    steps: tuple[tuple[float, int], ...]

    def to_camera(self, T: np.ndarray | float) -> np.ndarray:
        T = np.asarray(T, dtype=np.float64)
        shift = np.interp(T, self.anchor_times, self.anchor_offsets)
        return self.offset + self.rate * T + shift


def brightness(signal: np.ndarray) -> np.ndarray:
    """(n,) per-frame brightness in [~0, ~1] (step 1 of the module docstring)."""
    signal = np.asarray(signal, dtype=np.float64)
    lo = np.percentile(signal, 2.0, axis=0)
    hi = np.percentile(signal, 99.5, axis=0)
    span = np.where(hi - lo > 0, hi - lo, np.inf)
    return np.min((signal - lo) / span, axis=1)


def _crossing(b: np.ndarray, times: np.ndarray, i: int, step: int) -> float:
    """Time where ``b`` crosses 0.5 walking from bright frame ``i`` in direction ``step``."""
    j = i
    while 0 <= j + step < len(b) and b[j + step] >= _MID:
        j += step
    k = j + step
    if not 0 <= k < len(b):
        return np.nan
    inside, outside = b[j], b[k]
    fraction = (inside - _MID) / (inside - outside) if inside != outside else 0.5
    return float(times[j] + fraction * (times[k] - times[j]))


def bright_runs(b: np.ndarray, times: np.ndarray) -> list[Run]:
    """Runs of bright frames by hysteresis; runs touching the take's ends are left out."""
    bright = np.zeros(len(b), dtype=bool)
    state = False
    for i, value in enumerate(b):
        state = value > _HIGH if not state else value >= _LOW
        bright[i] = state
    runs = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], bright.astype(int), [0]])))
    for first, end in zip(edges[::2], edges[1::2], strict=True):
        last = end - 1
        if first == 0 or last == len(b) - 1:
            continue
        peak = first + int(np.argmax(b[first : last + 1]))
        rise, fall = _crossing(b, times, peak, -1), _crossing(b, times, peak, +1)
        if np.isfinite(rise) and np.isfinite(fall) and fall > rise:
            runs.append(Run(int(first), int(last), rise, fall))
    return runs


def _chains(runs: list[Run]) -> list[list[Run]]:
    """Groups of >= 2 runs of similar length, each separated by a gap of about that length."""
    chains, current = [], [runs[0]] if runs else []
    for run in runs[1:]:
        ref = float(np.median([r.length for r in current]))
        gap = run.rise - current[-1].fall
        if 0.5 < run.length / ref < 1.8 and 0.5 < gap / ref < 2.0:
            current.append(run)
        else:
            if len(current) >= 2:
                chains.append(current)
            current = [run]
    if len(current) >= 2:
        chains.append(current)
    return chains


def _mark_edges(patch: Patch) -> np.ndarray:
    """Player times of a mark's edges: rise, fall of each flash (frame f spans [f, f + 1))."""
    return np.array([t for a, b in patch.flashes for t in (a, b + 1)], dtype=np.float64)


def _marks(runs: list[Run], sequence: PatternSequence) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(mark number, player edges, camera edges) of every chain whose count names a mark."""
    by_count = {len(p.flashes): (g, p) for g, p in enumerate(sequence.of_kind("sync"))}
    out = []
    for chain in _chains(runs):
        if len(chain) in by_count:
            g, patch = by_count[len(chain)]
            edges = np.array([t for r in chain for t in (r.rise, r.fall)], dtype=np.float64)
            out.append((g, _mark_edges(patch), edges))
    return out


def _mark_shift(mark: tuple, offset: float, rate: float) -> int | None:
    """Whole camera frames a mark lies off the line (frames dropped or repeated between it and
    the marks that made the line), or None when its edges do not follow the line's rate."""
    _, T, t = mark
    residual = t - offset - rate * T
    shift = float(np.mean(residual))
    whole = round(shift)
    if np.max(np.abs(residual - shift)) > MARK_TOLERANCE or abs(shift - whole) > 0.35:
        return None
    return whole if abs(whole) <= MAX_STEP else None


def _level_fit(marks: list, level: list[int]) -> tuple[float, float]:
    """(offset, rate) of the line through the edges of marks ``level``."""
    T = np.concatenate([marks[k][1] for k in level])
    t = np.concatenate([marks[k][2] for k in level])
    rate, offset = np.polyfit(T, t, 1)
    return float(offset), float(rate)


def _place(marks: list, source: object) -> tuple[float, float, list[int]]:
    """(offset, rate, marks placed) by the pairwise search of step 4; a mark a whole number of
    frames off the line (a dropped frame between marks) is placed with that shift."""
    best: tuple[tuple[int, float, int], float, float, list[int]] | None = None
    for i, j in itertools.combinations(range(len(marks)), 2):
        if marks[i][0] == marks[j][0]:
            continue
        offset, rate = _level_fit(marks, [i, j])
        if not 0.05 < rate < 20:
            continue
        level = [k for k, m in enumerate(marks) if _mark_shift(m, offset, rate) == 0]
        if len({marks[k][0] for k in level}) < 2:
            continue
        offset, rate = _level_fit(marks, level)
        shifts = {k: _mark_shift(m, offset, rate) for k, m in enumerate(marks)}
        agree = [k for k, v in shifts.items() if v is not None]
        residuals = [marks[k][2] - offset - rate * marks[k][1] - shifts[k] for k in agree]
        spread = float(np.sqrt(np.mean(np.concatenate(residuals) ** 2)))
        key = (len({marks[k][0] for k in agree}), -spread, len(level))
        if best is None or key > best[0]:
            best = (key, offset, rate, agree)
    if best is None:
        found = len({g for g, _, _ in marks})
        if found >= 2:
            raise InputError(
                f"the take does not match the sequence: {found} of its sync marks (white "
                "flashes) are seen, but not at the times sequence.yaml puts them; is this the "
                "sequence that was played (its --hold and --fps)?",
                source=source,
            )
        raise InputError(
            f"the pattern sequence was not found in the take: {found} of its sync marks "
            "(white flashes) seen where at least 2 are needed; is this a take of that sequence, "
            "is the wall in frame and lit?",
            source=source,
        )
    return best[1], best[2], best[3]


def _window_mean(signal: np.ndarray, times: np.ndarray, lo: float, hi: float):
    inside = (times >= lo) & (times <= hi)
    if not np.any(inside):
        return None, None
    values = signal[inside]
    return np.median(values, axis=0), values


def _change_time(
    signal: np.ndarray, times: np.ndarray, t_hat: float, spans: tuple[float, float]
) -> float | None:
    """Where the take crosses half-way between the two patches meeting near ``t_hat``."""
    left, right = spans
    mu_l, vals_l = _window_mean(signal, times, t_hat - max(GUARD, left - GUARD), t_hat - GUARD)
    mu_r, vals_r = _window_mean(signal, times, t_hat + GUARD, t_hat + max(GUARD, right - GUARD))
    if mu_l is None or mu_r is None:
        return None
    d = mu_r - mu_l
    scale = float(d @ d)
    if scale <= 0:
        return None
    scatter = np.concatenate([(vals_l - mu_l) @ d, (vals_r - mu_r) @ d]) / np.sqrt(scale)
    sigma = 1.4826 * float(np.median(np.abs(scatter))) if len(scatter) > 2 else 0.0
    size = float(np.sqrt(scale))
    brighter = float(max(np.max(np.abs(mu_l)), np.max(np.abs(mu_r))))
    if size < CHANGE_SIGMAS * sigma or size < CHANGE_RELATIVE * brighter:
        return None
    near = np.flatnonzero((times > t_hat - GUARD - 1) & (times < t_hat + GUARD + 1))
    if len(near) < 2:
        return None
    s = (signal[near] - mu_l) @ d / scale
    ups = np.flatnonzero((s[:-1] < _MID) & (s[1:] >= _MID))
    if len(ups) != 1:
        return None
    k = ups[0]
    a, b = s[k], s[k + 1]
    t = times[near[k]] + (_MID - a) / (b - a) * (times[near[k + 1]] - times[near[k]])
    return float(t) if abs(t - t_hat) < 1.5 else None


def _flat_frames(patch: Patch, *, at_end: bool) -> int:
    """Frames of ``patch`` showing one colour next to its end (or start): all of a plain patch,
    a sync mark's black after its last flash (or before its first)."""
    if patch.kind != "sync":
        return patch.frames
    return patch.last - patch.flashes[-1][1] if at_end else patch.flashes[0][0] - patch.first


def _filter(r: np.ndarray, keep_mask: np.ndarray) -> np.ndarray:
    """Anchors whose offset agrees with the median of 3 neighbours on either side:
    an outlier agrees with neither, a step (dropped frame) with one side."""
    keep = np.ones(len(r), dtype=bool)
    for i in range(len(r)):
        if keep_mask[i]:
            continue  # the marks' own anchors are trusted
        left, right = r[max(0, i - 3) : i], r[i + 1 : i + 4]
        ok = [abs(r[i] - np.median(side)) < ANCHOR_TOLERANCE for side in (left, right) if len(side)]
        keep[i] = any(ok) if ok else True
    return keep


def _step_gaps(r: np.ndarray) -> list[int]:
    """Gaps ``j`` (between anchors j and j + 1) where the offset steps by a frame or more: the
    medians of up to 3 anchors either side differ by over :data:`STEP_THRESHOLD`; of adjacent
    such gaps, the one with the largest jump between its own two anchors."""
    flagged = [
        j
        for j in range(len(r) - 1)
        if abs(np.median(r[j + 1 : j + 5]) - np.median(r[max(0, j - 3) : j + 1])) > STEP_THRESHOLD
    ]
    groups: list[list[int]] = []
    for j in flagged:
        if groups and j - groups[-1][-1] <= 3:
            groups[-1].append(j)
        else:
            groups.append([j])
    return [max(group, key=lambda j: abs(r[j + 1] - r[j])) for group in groups]


def _smooth(T: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, tuple[tuple[float, int], ...]]:
    """Offsets fitted by a line per segment between steps (averaging the anchors' sub-frame
    timing scatter), and the steps as (player frame, frames)."""
    gaps = _step_gaps(r)
    bounds = [0, *(j + 1 for j in gaps), len(r)]
    smooth = np.empty_like(r)
    for a, b in itertools.pairwise(bounds):
        if b - a >= 3:
            slope, intercept = np.polyfit(T[a:b], r[a:b], 1)
            smooth[a:b] = intercept + slope * T[a:b]
        else:
            smooth[a:b] = np.mean(r[a:b])
    steps = tuple(
        (
            float(T[j + 1]),
            int(np.round(np.median(r[j + 1 : j + 5]) - np.median(r[max(0, j - 3) : j + 1]))),
        )
        for j in gaps
    )
    return smooth, steps


def align_take(
    signal: np.ndarray, times: np.ndarray, sequence: PatternSequence, *, source: object = None
) -> Alignment:
    """Align a take (``signal`` (n, 3) per-frame wall means at frame times ``times``) to
    ``sequence`` (steps 1-5 of the module docstring).

    Raises
    ------
    InputError
        When fewer than two sync marks are found consistently (not this sequence, or no wall).
    """
    signal = np.asarray(signal, dtype=np.float64)
    times = np.asarray(times, dtype=np.float64)
    runs = bright_runs(brightness(signal), times)
    marks = _marks(runs, sequence)
    offset, rate, agree = _place(marks, source)
    T_list, r_list, trusted = [], [], []
    for k in agree:
        _, mark_frames, mark_times = marks[k]
        T_list.append(float(np.mean(mark_frames)))
        r_list.append(float(np.mean(mark_times - offset - rate * mark_frames)))
        trusted.append(True)
    mark_T, mark_r = np.array(T_list), np.array(r_list)
    order = np.argsort(mark_T)
    rough = (mark_T[order], mark_r[order])
    for i in range(1, len(sequence.patches)):
        before, after = sequence.patches[i - 1], sequence.patches[i]
        T = float(after.first)
        t_hat = offset + rate * T + float(np.interp(T, *rough))
        spans = (rate * _flat_frames(before, at_end=True), rate * _flat_frames(after, at_end=False))
        t = _change_time(signal, times, t_hat, spans)
        if t is not None:
            T_list.append(T)
            r_list.append(t - offset - rate * T)
            trusted.append(False)
    T_all, r_all, trusted_all = np.array(T_list), np.array(r_list), np.array(trusted)
    order = np.argsort(T_all, kind="stable")
    T_all, r_all, trusted_all = T_all[order], r_all[order], trusted_all[order]
    keep = _filter(r_all, trusted_all)
    T_all, r_all = T_all[keep], r_all[keep]
    r_all, steps = _smooth(T_all, r_all)
    return Alignment(
        rate=rate,
        offset=offset,
        anchor_times=T_all,
        anchor_offsets=r_all,
        marks_found=tuple(sorted({marks[k][0] for k in agree})),
        marks_expected=len(sequence.of_kind("sync")),
        changes_used=int(np.count_nonzero(~trusted_all[keep])),
        steps=steps,
    )


def kept_frames(alignment: Alignment, patch: Patch, times: np.ndarray) -> np.ndarray:
    """Indices of the frames inside ``patch``, :data:`GUARD` frames from both changes."""
    start, end = alignment.to_camera(np.array([patch.first, patch.last + 1], dtype=np.float64))
    times = np.asarray(times, dtype=np.float64)
    return np.flatnonzero((times >= start + GUARD) & (times <= end - GUARD))
