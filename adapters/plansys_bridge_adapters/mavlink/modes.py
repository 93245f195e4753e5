"""ArduPilot flight modes (custom_mode numbers) and the MAVLink vehicle types.

The numbers are ArduCopter's and ArduRover's ``custom_mode`` values as carried in
HEARTBEAT and set with MAV_CMD_DO_SET_MODE; they are kept here, not read from
pymavlink's tables, because both the client and the vehicle double must agree on
them and on which model a HEARTBEAT type means.
"""

from __future__ import annotations

from typing import Literal

Model = Literal["copter", "rover"]

COPTER_MODES: dict[str, int] = {
    "STABILIZE": 0,
    "ACRO": 1,
    "ALT_HOLD": 2,
    "AUTO": 3,
    "GUIDED": 4,
    "LOITER": 5,
    "RTL": 6,
    "CIRCLE": 7,
    "LAND": 9,
    "DRIFT": 11,
    "SPORT": 13,
    "FLIP": 14,
    "AUTOTUNE": 15,
    "POSHOLD": 16,
    "BRAKE": 17,
    "THROW": 18,
    "AVOID_ADSB": 19,
    "GUIDED_NOGPS": 20,
    "SMART_RTL": 21,
}

ROVER_MODES: dict[str, int] = {
    "MANUAL": 0,
    "ACRO": 1,
    "STEERING": 3,
    "HOLD": 4,
    "LOITER": 5,
    "FOLLOW": 6,
    "SIMPLE": 7,
    "AUTO": 10,
    "RTL": 11,
    "SMART_RTL": 12,
    "GUIDED": 15,
    "INITIALISING": 16,
}

# MAV_TYPE values in HEARTBEAT.type for each model.
MAV_TYPE_QUADROTOR = 2
MAV_TYPE_GROUND_ROVER = 10
COPTER_TYPES = frozenset({2, 3, 4, 13, 14, 15})  # quad, coax, heli, hexa, octo, tri
ROVER_TYPES = frozenset({10, 11})  # ground rover, surface boat
MAV_AUTOPILOT_ARDUPILOTMEGA = 3


def mode_table(model: Model) -> dict[str, int]:
    """The name -> custom_mode table of ``model``."""
    return COPTER_MODES if model == "copter" else ROVER_MODES


def mode_number(model: Model, name: str) -> int:
    """``custom_mode`` of the mode called ``name`` (case-insensitive); KeyError if unknown."""
    return mode_table(model)[name.upper()]


def mode_name(model: Model, number: int) -> str:
    """Name of ``custom_mode`` ``number``; ``MODE(<n>)`` when the table does not know it."""
    for name, value in mode_table(model).items():
        if value == number:
            return name
    return f"MODE({number})"


def model_of_type(mav_type: int) -> Model | None:
    """The model a HEARTBEAT ``type`` stands for, or None for anything else."""
    if mav_type in COPTER_TYPES:
        return "copter"
    if mav_type in ROVER_TYPES:
        return "rover"
    return None
