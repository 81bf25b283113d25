"""What the suction's feedback says about the vacuum, for the driver solve's messages
(:mod:`ur3hanoi.interface.urdriver.solve`).

A grasp whose vacuum switch stays 0 is a missing block, unless the vacuum sensor reads the calibration's no-vacuum
level (nearer its ``ain0_off`` than its ``ain0_free``) while the cup's output is on: then the cell makes no vacuum at
all (the generator off, a wrong pin, no air), and the message names the pins to check
(:class:`~ur3hanoi.station.suction_wiring.SuctionWiring`), with the outputs as ``io_states`` reads them.
"""

from __future__ import annotations

from ur3hanoi.interface.urdriver.io import IoStates
from ur3hanoi.station.suction_profile import SuctionProfile
from ur3hanoi.station.suction_wiring import GENERATOR_KEY, SuctionWiring, output_name


def feedback_text(io: IoStates | None, w: SuctionWiring, outputs: bool = False) -> str:
    """``DI0=0, AI0=1.05 V`` (with ``outputs``: and the suction's outputs as ``io_states`` reads them)."""
    if io is None:
        return "no io_states"
    text = f"DI{w.switch_input}={int(io.digital_in[w.switch_input])}, AI{w.sensor_input}=" \
           f"{io.analog_in[w.sensor_input][1]:.2f} V"
    return text + "".join(f", DO{pin}={int(io.digital_out[pin])}" for pin in w.outputs) if outputs else text


def no_vacuum(io: IoStates | None, w: SuctionWiring, profile: SuctionProfile) -> bool:
    """The vacuum sensor reads the calibration's no-vacuum level though the cup's output is on."""
    if io is None or not io.digital_out[w.output]:
        return False
    volts = io.analog_in[w.sensor_input][1]
    return abs(volts - profile.ain0_off) < abs(volts - profile.ain0_free)


def vacuum_hint(w: SuctionWiring) -> str:
    """What to check when the cup's output is on and the sensor reads no vacuum: the generator's pin."""
    cup = f"The cup's {output_name(w.output)} (io.suction_output) is on but the vacuum sensor reads no vacuum"
    if w.generator is None:
        return (f". {cup}, and the calibration names no vacuum generator output (io.{GENERATOR_KEY}): if the "
                "cell switches its generator from the robot (ENME480's UR3e: set_io pin 12, configurable "
                f"output 4), write that pin into io.{GENERATOR_KEY}")
    return (f". {cup}, with the vacuum generator's {output_name(w.generator)} (io.{GENERATOR_KEY}) on since the "
            "start: is that the generator's pin (the pendant's I/O tab shows which output makes the vacuum), "
            "and does the generator have air?")
