"""The taught-points file of a teach session: every record written at once, atomically, in the taught-points
format ``calibrate --taught`` reads (:mod:`ur3hanoi.calibrate.taught`), in degrees as on the pendant, one point a line.

A session on an existing file continues it: its points are read back (strictly: an invalid file is an error that
names it, and nothing is written). A file in radians, one taught for another station (its ``station`` names
another calibration) or one with a slot outside the base calibration's grid is refused, and left as it was.

Recording a slot again replaces its point (a re-recorded pose is the better one); undo removes the last point, and
the file itself when it was the only one (a taught-points file holds at least one point).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from ur3hanoi.calibrate.taught import DEG_DECIMALS, TaughtPoint, TaughtPoints, load_taught, taught_text
from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.io.atomic import atomic_write
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON
from ur3hanoi.tables import Slot
from ur3hanoi.tables.ik_table import pose_label


def _rounded(q: tuple[float, ...]) -> tuple[float, ...]:
    """``q`` [rad] as the file holds it: each angle rounded to :data:`DEG_DECIMALS` decimals of a degree (read
    back, the file gives these very floats)."""
    return tuple(math.radians(round(math.degrees(v), DEG_DECIMALS)) for v in q)


@dataclass(frozen=True)
class TaughtFile:
    """The points of one session and the file they live in.

    Attributes:
        path: the taught-points file.
        station: the base calibration's name (written as the file's ``station``).
        base_label: how the file's header names the base calibration (``lab_real``, ``my_base.yaml``).
        points: the points, in file order (joint angles [rad], as the file holds them).
        protected: files the session must never write (the base calibration).
    """

    path: Path
    station: str
    base_label: str
    points: tuple[TaughtPoint, ...] = ()
    protected: tuple[Path, ...] = ()

    @property
    def slots(self) -> tuple[Slot, ...]:
        return tuple((p.tower, p.height, p.k) for p in self.points)

    def taught(self) -> TaughtPoints:
        """The points as :func:`ur3hanoi.calibrate.fit_station` takes them."""
        return TaughtPoints(points=self.points, source=str(self.path), sha256="", units="deg", station=self.station)

    def text(self) -> str:
        header = (f"Taught with `ur3hanoi teach` for {self.base_label}: joint angles [deg] as on the pendant "
                  "(controller convention), one contact pose a line, towers and heights from 1.",
                  f"Calibrate by hand: ur3hanoi calibrate --taught {self.path.name} --base {self.base_label} -o "
                  "station.yaml")
        return taught_text(self.points, self.station, [printable(h, 4096) for h in header])

    def with_point(self, tower: int, height: int, q: tuple[float, ...]) -> tuple[TaughtFile, str]:
        """A copy with the contact pose ``q`` [rad] at (tower, height) (0-based) recorded, replacing any earlier
        point of that slot; and what happened, for people."""
        kept = [p for p in self.points if (p.tower, p.height, p.k) != (tower, height, ON)]
        replaced = len(kept) < len(self.points)
        kept.append(TaughtPoint(index=0, tower=tower, height=height, k=ON, q=_rounded(q)))
        new = replace(self, points=tuple(replace(p, index=i) for i, p in enumerate(kept)))
        label = pose_label(tower, height, ON).removesuffix(" on")
        what = f"recorded {label}" + (" again (the earlier pose is replaced)" if replaced else "")
        return new, f"{what}: point {len(kept)} of {printable(self.path)}"

    def without_last(self) -> tuple[TaughtFile, str]:
        """A copy without the last point; and what happened."""
        if not self.points:
            return self, "nothing to undo: no point recorded yet"
        last = self.points[-1]
        return replace(self, points=self.points[:-1]), f"undone: {last.label} removed"

    def save(self) -> None:
        """Write the file atomically (remove it when no point is left: a taught-points file holds one at least).

        Raises:
            OutputError: the file cannot be written; the old one is left as it was.
        """
        if self.points:
            atomic_write(self.path, self.text(), inputs=self.protected)
        else:
            self.path.unlink(missing_ok=True)


def open_taught(path: str | Path, base: Station, base_label: str, protected: tuple[Path, ...] = ()) -> TaughtFile:
    """The session of ``path``: empty when there is no such file, else its points (continued).

    Raises:
        TaughtPointsError: the file is invalid, in radians, taught for another station, or has a point outside
            ``base``'s grid; the message names the file and what to do.
    """
    path = Path(path)
    empty = TaughtFile(path=path, station=base.name, base_label=base_label, protected=protected)
    if not path.exists() and not path.is_symlink():
        return empty
    old = load_taught(path)
    where = printable(path)
    if old.units != "deg":
        raise TaughtPointsError(f"{where}: units: {old.units}: teach records degrees, as on the pendant: continue in "
                                "a new file, or convert this one to units: deg", source=str(path))
    if old.station and old.station != base.name:
        raise TaughtPointsError(f"{where}: taught for station {printable(old.station)!r}, not for "
                                f"{printable(base.name)!r} ({printable(base_label)}): give --base the calibration it "
                                "was taught for, or teach into a new file", source=str(path))
    for p in old.points:
        if not (0 <= p.tower < base.n_towers and 0 <= p.height < base.n_heights):
            raise TaughtPointsError(f"{where}: {p.label} is outside the grid of {printable(base_label)} (towers "
                                    f"1..{base.n_towers}, heights 1..{base.n_heights}): is it another station's "
                                    "file?", source=str(path))
    return replace(empty, points=old.points)


__all__ = ["TaughtFile", "open_taught"]
