"""Whether the ROS master a node registered with is still there, asked in a thread of its own.

A rospy node never notices that its master is gone: the connections it has keep working, while no new node can find
it (``rosgraph.is_master_online()`` is false) and, if another master starts on the port, that one knows nothing of
it. :class:`MasterWatch` asks the master for its pid (``getPid``) every :data:`WATCH_PERIOD_S`; the master is lost
when nothing listens on its port any more, when another master (another pid) answers there, or when it accepts
connections but gives no answer for :data:`NO_ANSWER_S` -- so it is noticed within about a second, well within 2 s.
Then ``on_lost(reason)`` runs in the watch thread: ``ros-station`` starts its own master again and registers again
(:func:`reregister`), ``ros-solve`` stops (:class:`ur3hanoi.interface.ros1.client.RosArm`).

Helpers on rospy's registration: :func:`quick_shutdown` takes 0.5 s off rospy's shutdown (a station stops in 0.5 s
instead of 1 s); :func:`forget_master` keeps rospy from unregistering with a master that is gone (or not the node's)
when it shuts down: rospy's XML-RPC calls have no time limit, and a master that accepts and never answers would hold
the exit.
"""

from __future__ import annotations

import contextlib
import importlib
import threading
import time
from collections.abc import Callable
from typing import Any

from ur3hanoi.interface.ros1.errors import RosError
from ur3hanoi.interface.ros1.master import MasterUri, probe_master

WATCH_PERIOD_S = 0.25
"""How often [s] the master is asked for its pid."""
NO_ANSWER_S = 1.0
"""A master that accepts connections but has not answered for this long [s] is gone."""
_ASK_TIMEOUT_S = 0.5


class MasterWatch:
    """Ask the master at ``uri`` (process ``pid``) for its pid every ``period_s`` in a daemon thread.

    Args:
        uri: the master URI.
        pid: the process id the master answered with when the node registered.
        on_lost: called in the watch thread with the reason once the master is lost; returns the pid of the master
            to watch from now on (one started again), or None to stop watching (:attr:`lost` keeps the reason).
        period_s: how often [s] to ask.
    """

    def __init__(self, uri: str, pid: int, on_lost: Callable[[str], int | None] = lambda _reason: None,
                 period_s: float = WATCH_PERIOD_S) -> None:
        self.uri = uri
        self.pid = pid
        self.on_lost = on_lost
        self.period_s = period_s
        self._lost: str | None = None
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="ur3hanoi-master-watch", daemon=True)

    @property
    def lost(self) -> str | None:
        """Why the master is gone (and was not replaced by ``on_lost``), or None while it answers."""
        return self._lost

    def start(self) -> MasterWatch:
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop watching (waits for an ``on_lost`` in progress)."""
        self._stopping.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join()

    def __enter__(self) -> MasterWatch:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def check(self, answered_s: float) -> str | None:
        """Ask once; the reason the master is gone, or None while it is there (``answered_s``: seconds since it
        last answered)."""
        try:
            pid = probe_master(self.uri, timeout=_ASK_TIMEOUT_S)
        except RosError:  # accepts connections, no answer like a master's
            if answered_s >= NO_ANSWER_S:
                return f"it accepts connections but has not answered for {answered_s:.1f} s"
            return None
        if pid is None:
            return f"nothing listens on port {MasterUri.parse(self.uri).port} any more"
        if pid != self.pid:
            return f"another master (pid {pid}) answers there now"
        return None

    def _run(self) -> None:
        answered = time.monotonic()
        while not self._stopping.wait(self.period_s):
            reason = self.check(time.monotonic() - answered)
            if reason is None:
                answered = time.monotonic()
                continue
            self._lost = reason
            pid = self.on_lost(reason)
            if pid is None:
                return
            self.pid, self._lost, answered = pid, None, time.monotonic()


def _registration() -> Any:
    """``rospy.impl.registration`` (rospy is Debian's, outside the type checker's view)."""
    return importlib.import_module("rospy.impl.registration")


def _reg_manager() -> Any:
    """rospy's registration manager of this node (the one that talks to the master), or None."""
    registration = _registration()
    listeners = registration.get_registration_listeners()
    return next((x for x in listeners.listeners if isinstance(x, registration.RegManager)), None)


def reregister() -> int:
    """Register this rospy node's publishers and subscribers with its master again (one started again knows none of
    them; each subscriber learns the publishers the master knows); returns how many were registered."""
    registration = _registration()
    reg, topics, how = _reg_manager(), registration.get_topic_manager(), registration.Registration
    if reg is None or topics is None:
        return 0
    entries = [(name, kind, how.PUB) for name, kind in topics.get_publications()]
    entries += [(name, kind, how.SUB) for name, kind in topics.get_subscriptions()]
    for name, kind, reg_type in entries:
        reg.reg_added(name, kind, reg_type)
    return len(entries)


def quick_shutdown() -> None:
    """Make this rospy node's shutdown 0.5 s shorter (call after ``init_node``): rospy waits for its registration
    thread, which sleeps on a condition 0.5 s at a time and is woken only before rospy raises its shutdown flag;
    waking it once more after the flag lets it end at once."""
    reg = _reg_manager()
    if reg is None:
        return

    def wake(_reason: str) -> None:
        with reg.cond:
            reg.cond.notify_all()

    importlib.import_module("rospy.core").add_shutdown_hook(wake)


def forget_master() -> None:
    """Keep rospy from unregistering with its master when it shuts down (the master is gone, or not this node's)."""
    with contextlib.suppress(ImportError):
        reg = _reg_manager()
        if reg is not None:
            reg.master_uri = None


def raise_if_lost(watch: MasterWatch | None, uri: str, ask: str) -> None:
    """A client's check between its steps: :class:`RosError` once ``watch``'s master is gone (``ask``: what the user
    should look at)."""
    lost = None if watch is None else watch.lost
    if lost is not None:
        raise RosError(f"the ROS master at {uri} is gone ({lost}): ros-solve stops; is {ask} still running?")


def end_client(watch: MasterWatch | None, rospy: Any) -> None:
    """A client's end: stop watching the master and shut the node down (not unregistering with a master that is
    gone)."""
    if watch is not None:
        watch.stop()
        if watch.lost is not None:
            forget_master()
    if rospy is not None:
        rospy.signal_shutdown("ur3hanoi ros-solve done")


__all__ = ["NO_ANSWER_S", "WATCH_PERIOD_S", "MasterWatch", "end_client", "forget_master", "quick_shutdown",
           "raise_if_lost", "reregister"]
