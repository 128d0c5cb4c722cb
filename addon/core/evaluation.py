"""Scores a track against the truth: the thesis's Table 5.1 and more.

Azimuths are compared in the scene's world frame (azimuth + north offset of
each file), so a track that does not know north (offset 0, azimuths relative
to +Y) is scored correctly against a geographic truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Sequence, Tuple

from .angles import (angle_between_deg, azimuth_difference_deg, azimuth_world_from_geographic,
                     sun_in_world_from_angles)
from .trackfile import Track

__all__ = ["angle_between_deg", "azimuth_difference_deg", "direction", "evaluate"]


def direction(zenith_deg: float, azimuth_world_deg: float) -> Tuple[float, float, float]:
    """angles.sun_in_world_from_angles as a tuple (kept for its callers)."""
    x, y, z = sun_in_world_from_angles(zenith_deg, azimuth_world_deg)
    return float(x), float(y), float(z)


@dataclass
class Stats:
    min: float
    max: float
    mean: float

    @staticmethod
    def of(values: Sequence[float]) -> Optional["Stats"]:
        if not values:
            return None
        return Stats(min(values), max(values), sum(values) / len(values))


@dataclass
class SceneReport:
    name: str
    frames_total: int
    frames_estimated: int
    zenith: Optional[Stats] = None
    azimuth: Optional[Stats] = None
    direction: Optional[Stats] = None
    initial_error_deg: Optional[float] = None
    message: Optional[str] = None
    # Per frame, for plots: frame, truth z/a (world), estimate z/a (world).
    series: List[tuple] = field(default_factory=list)


def evaluate(name: str, track: Optional[Track], truth: Track,
             message: Optional[str] = None) -> SceneReport:
    """Per-frame errors of `track` against `truth` (frames matched by number)."""
    report = SceneReport(name=name, frames_total=len(truth.frames), frames_estimated=0,
                         message=message)
    if track is None:
        report.message = message or "no track"
        return report
    est_by_frame = {f.frame: f for f in track.frames}
    dz, da, dd = [], [], []
    for t in truth.frames:
        # Explicit None tests (not has_estimate) let mypy see the floats.
        if t.zenith_deg is None or t.azimuth_deg is None:
            continue
        t_az = azimuth_world_from_geographic(t.azimuth_deg, truth.north_offset_deg)
        e = est_by_frame.get(t.frame)
        e_z = e_az = None
        if e is not None and e.zenith_deg is not None and e.azimuth_deg is not None:
            e_z = e.zenith_deg
            e_az = azimuth_world_from_geographic(e.azimuth_deg, track.north_offset_deg)
            dz.append(abs(e_z - t.zenith_deg))
            da.append(azimuth_difference_deg(e_az, t_az))
            dd.append(angle_between_deg(sun_in_world_from_angles(e_z, e_az),
                                        sun_in_world_from_angles(t.zenith_deg, t_az)))
        report.series.append((t.frame, t.zenith_deg, t_az, e_z, e_az))
    report.frames_estimated = len(dz)
    report.zenith, report.azimuth, report.direction = Stats.of(dz), Stats.of(da), Stats.of(dd)
    init = track.initial or {}
    if init.get("zenith_deg") is not None and init.get("azimuth_deg") is not None and truth.frames:
        # The initial Sun's own frame (a run may anchor past frame 1).
        first = truth.frame(init["frame"]) if init.get("frame") is not None else None
        first = first if first is not None and first.has_estimate else truth.frames[0]
        if first.zenith_deg is not None and first.azimuth_deg is not None:
            report.initial_error_deg = angle_between_deg(
                sun_in_world_from_angles(init["zenith_deg"], azimuth_world_from_geographic(
                    init["azimuth_deg"], track.north_offset_deg)),
                sun_in_world_from_angles(first.zenith_deg, azimuth_world_from_geographic(
                    first.azimuth_deg, truth.north_offset_deg)))
    if report.frames_estimated == 0 and report.message is None:
        report.message = (track.extra.get("message") if track.extra else None) or \
            "the track has no estimates"
    return report


@dataclass
class ReliabilityBin:
    """Frames whose confidence lies in [lo, hi): how many, their mean
    confidence, and the share of them within the reliability's limit."""
    lo: float
    hi: float
    frames: int
    mean_confidence: float
    share_within: float


def reliability(frames: Sequence[Tuple[float, float]], within_deg: float = 2.0,
                bins: int = 10) -> Tuple[List[ReliabilityBin], Optional[float]]:
    """How far confidence is a probability: frames (error deg, confidence)
    in `bins` equal bins of confidence (1.0 in the last), each bin's share of
    frames within `within_deg`, and the expected calibration error (the
    frames' mean gap between confidence and that share; None without
    frames). A frame at confidence c should be within with probability c."""
    rows: List[ReliabilityBin] = []
    gap = 0.0
    for b in range(bins):
        lo, hi = b / bins, (b + 1) / bins
        inside = [(e, c) for e, c in frames if lo <= c < hi or (b == bins - 1 and c == hi)]
        if not inside:
            continue
        mean_c = sum(c for _, c in inside) / len(inside)
        share = sum(e <= within_deg for e, _ in inside) / len(inside)
        rows.append(ReliabilityBin(lo, hi, len(inside), mean_c, share))
        gap += len(inside) * abs(share - mean_c)
    return rows, (gap / len(frames) if frames else None)


def _fmt(v: Optional[float]) -> str:
    return "-" if v is None else f"{v:.2f}°"


def format_table(reports: Sequence[SceneReport]) -> str:
    """The thesis's Table 5.1 layout, one column per scene, plus our rows."""
    rows = [
        ("Zenith Min Error", lambda r: r.zenith and r.zenith.min),
        ("Zenith Max Error", lambda r: r.zenith and r.zenith.max),
        ("Zenith Mean Error", lambda r: r.zenith and r.zenith.mean),
        ("Azimuth Min Error", lambda r: r.azimuth and r.azimuth.min),
        ("Azimuth Max Error", lambda r: r.azimuth and r.azimuth.max),
        ("Azimuth Mean Error", lambda r: r.azimuth and r.azimuth.mean),
        ("Direction Mean Error", lambda r: r.direction and r.direction.mean),
        ("Direction Max Error", lambda r: r.direction and r.direction.max),
        ("Initial Sun Error", lambda r: r.initial_error_deg),
    ]
    width = max([20] + [len(r.name) + 2 for r in reports])
    lines = ["".ljust(22) + "".join(r.name.rjust(width) for r in reports)]
    for label, get in rows:
        lines.append(label.ljust(22) + "".join(_fmt(get(r)).rjust(width) for r in reports))
    lines.append("Frames estimated".ljust(22) + "".join(
        f"{r.frames_estimated}/{r.frames_total}".rjust(width) for r in reports))
    notes = [f"  {r.name}: {r.message}" for r in reports if r.message]
    if notes:
        lines.append("Notes:")
        lines.extend(notes)
    return "\n".join(lines)


def plot(report: SceneReport, path: str) -> Optional[str]:
    """Estimated vs true zenith and azimuth over frames (thesis figs 5.2-5.6).
    Returns the path written, or None when matplotlib is missing."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    frames = [s[0] for s in report.series]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, k, label in ((axes[0], 1, "Zenith"), (axes[1], 2, "Azimuth (world)")):
        ax.plot(frames, [s[k] for s in report.series], "k-", label="truth")
        est = [(s[0], s[k + 2]) for s in report.series if s[k + 2] is not None]
        if est:
            ax.plot([e[0] for e in est], [e[1] for e in est], "r.", ms=3, label="estimate")
        ax.set_xlabel("frame")
        ax.set_ylabel(f"{label} (deg)")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(report.name + ("" if not report.message else f" — {report.message}"), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def isotonic_fit(frames: Sequence[Tuple[float, float]], within_deg: float = 2.0,
                 min_block: int = 1) -> List[Tuple[float, float]]:
    """The calibration that makes confidence a probability: frames (error
    deg, confidence), the share of frames within `within_deg` as a
    non-decreasing function of confidence (pool adjacent violators), as knots
    (mean confidence of a block, its share) to interpolate between. Blocks
    of fewer than `min_block` frames are pooled with a neighbour, so one
    frame cannot set a knot. Empty without frames."""
    # Frames of one confidence are one block from the start: sorted, the
    # misses of a tie would come first and split it into a 0 and a 1.
    ties: dict = {}
    for e, c in frames:
        block = ties.setdefault(c, [0.0, 0.0, 0.0])
        block[0] += c
        block[1] += 1.0 if e <= within_deg else 0.0
        block[2] += 1.0
    # Each block: [sum of confidences, sum of hits, frames].
    blocks: List[List[float]] = []

    def merge_last() -> None:
        top = blocks.pop()
        blocks[-1] = [a + b for a, b in zip(blocks[-1], top)]
    for c in sorted(ties):
        blocks.append(list(ties[c]))
        while len(blocks) > 1 and (blocks[-2][1] / blocks[-2][2] >= blocks[-1][1] / blocks[-1][2]
                                   or blocks[-2][2] < min_block):
            merge_last()
    if len(blocks) > 1 and blocks[-1][2] < min_block:
        merge_last()
    return [(s_c / n, s_hit / n) for s_c, s_hit, n in blocks]
