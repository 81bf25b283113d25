"""The joint positions a driver client received, kept for a look at the path afterwards: :class:`JointRecord`.

A binding's transport adds every ``/joint_states`` message to its record (:meth:`JointRecord.add`, from its callback
thread; a copy into preallocated arrays, nothing computed); the solve starts the record where the plan starts, sets
:attr:`JointRecord.label` to the stretch of the plan it is executing (each sample keeps the label it arrived under),
stops it where the plan ends, and then measures the path (:mod:`~ur3hanoi.interface.urdriver.path_deviation`).

Memory is bounded: :data:`CAPACITY` samples (3.7 MB). That holds a whole solve at the driver's own rate, every
message: 27 s of a 3-block lab solve at 500 Hz (the e-Series) is 14,000 messages, at 125 Hz (CB3) 3,400, and even at a
slider of 25 % both fit. A longer recording keeps every second message it already has and from then on every second
one it receives (:attr:`JointRecord.stride` doubles), so the whole solve stays covered, more coarsely.
"""

from __future__ import annotations

import threading

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS

CAPACITY = 1 << 16
"""Samples a record holds before it thins (65,536: 131 s at 500 Hz, 524 s at 125 Hz)."""


class JointRecord:
    """Joint positions [rad] (controller order) with their time of arrival [s], while recording.

    Args:
        capacity: samples held before thinning (even, at least 2).
    """

    def __init__(self, capacity: int = CAPACITY) -> None:
        if capacity < 2 or capacity % 2:
            raise ValueError(f"capacity {capacity!r} is invalid: expected an even number >= 2")
        self._t = np.empty(capacity)
        self._q = np.empty((capacity, len(CONTROLLER_JOINTS)))
        self._label = np.empty(capacity, dtype=np.intp)
        self.label = 0
        """What the recorder is doing now (the solve: the index of the plan's stretch); stored with each sample."""
        self._n = 0
        self._seen = 0
        self.stride = 1
        """Every how many received messages one is kept (1 until the record first filled up)."""
        self.recording = False
        self._lock = threading.Lock()

    def start(self) -> None:
        """Forget what was recorded and record from the next message on."""
        with self._lock:
            self._n = self._seen = self.label = 0
            self.stride = 1
            self.recording = True

    def stop(self) -> None:
        """Stop recording (what was recorded stays)."""
        self.recording = False

    def add(self, t: float, q: FloatArray) -> None:
        """One received message: the time of arrival ``t`` [s] and ``q`` (6,) [rad] (ignored unless recording)."""
        if not self.recording:
            return
        with self._lock:
            self._seen += 1
            if (self._seen - 1) % self.stride:
                return
            if self._n == len(self._t):
                half = self._n // 2
                self._t[:half] = self._t[0:self._n:2]
                self._q[:half] = self._q[0:self._n:2]
                self._label[:half] = self._label[0:self._n:2]
                self._n, self.stride = half, 2 * self.stride  # this message's index is a multiple of it (even n)
            self._t[self._n] = t
            self._q[self._n] = q
            self._label[self._n] = self.label
            self._n += 1

    def samples(self) -> tuple[FloatArray, FloatArray, npt.NDArray[np.intp]]:
        """Copies of the recorded times (n,) [s], joint positions (n, 6) [rad] and labels (n,), in the order
        received."""
        with self._lock:
            n = self._n
            return self._t[:n].copy(), self._q[:n].copy(), self._label[:n].copy()

    @property
    def received(self) -> int:
        """Messages received while recording (kept or thinned out)."""
        return self._seen
