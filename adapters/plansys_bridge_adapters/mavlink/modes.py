"""ArduPilot flight modes (custom_mode numbers) and the MAVLink vehicle types.

The tables are pymavlink's (``mavutil.mode_mapping_acm`` for ArduCopter,
``mode_mapping_rover`` for ArduRover, and ``AP_MAV_TYPE_MODE_MAP`` for which
HEARTBEAT type flies which firmware), so the client, the vehicle double and
other pymavlink ground stations agree on every number.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

from pymavlink import mavutil

Model = Literal["copter", "rover"]

_BY_NUMBER: Mapping[Model, Mapping[int, str]] = {
    "copter": mavutil.mode_mapping_acm,
    "rover": mavutil.mode_mapping_rover,
}
_BY_NAME: Mapping[Model, Mapping[str, int]] = {
    model: {name: number for number, name in table.items()} for model, table in _BY_NUMBER.items()
}

# MAV_TYPE values the double sends in HEARTBEAT.type for each model.
MAV_TYPE_QUADROTOR = 2
MAV_TYPE_GROUND_ROVER = 10
MAV_AUTOPILOT_ARDUPILOTMEGA = 3


def mode_table(model: Model) -> Mapping[str, int]:
    """The name -> custom_mode table of ``model``."""
    return _BY_NAME[model]


def mode_number(model: Model, name: str) -> int:
    """``custom_mode`` of the mode called ``name`` (case-insensitive); KeyError if unknown."""
    return _BY_NAME[model][name.upper()]


def mode_name(model: Model, number: int) -> str:
    """Name of ``custom_mode`` ``number``; ``MODE(<n>)`` when the table does not know it."""
    return _BY_NUMBER[model].get(number, f"MODE({number})")


def model_of_type(mav_type: int) -> Model | None:
    """The model a HEARTBEAT ``type`` stands for (ArduCopter's frames: copter;
    ArduRover's rover and boat: rover), or None for anything else."""
    table = mavutil.mode_mapping_bynumber(mav_type)
    for model, known in _BY_NUMBER.items():
        if table is known:
            return model
    return None
