"""MAVLink adapter: ArduPilot copters and rovers as plan action performers.

``vehicle`` is an asyncio client for one vehicle over any pymavlink connection string,
``performer`` turns plan actions into vehicle commands, ``telemetry`` feeds battery
readings into the knowledge base, and ``double`` is a MAVLink vehicle simulator that
behaves like ArduCopter / ArduRover SITL for tests and demos.
"""
