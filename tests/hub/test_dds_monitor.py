"""``plansys-bridge monitor`` in its own process watches a mission run over DDS."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from test_dds_processes import read_line, write_mission

from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

pytestmark = pytest.mark.timeout(120)


def test_monitor_shows_plans_actions_winners_performers_and_knowledge(tmp_path: Path) -> None:
    path = write_mission(tmp_path)
    mission = load_mission(path)
    domain_id = mission.transport.domain_id
    monitor = subprocess.Popen(
        [sys.executable, "-m", "plansys_bridge", "monitor", "--domain-id", str(domain_id)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ | {"PYTHONUNBUFFERED": "1"},
    )
    try:
        first = read_line(monitor, timeout=30)
        assert first.strip() == f"monitoring DDS domain {domain_id} (Ctrl-C to stop)"
        report = run_mission(mission, out=None)  # executor and performers in this process
        assert report.success, report.summary()
        assert report.result is not None
        monitor.send_signal(signal.SIGINT)
        out, err = monitor.communicate(timeout=30)
    finally:
        if monitor.poll() is None:
            monitor.kill()
            monitor.communicate(timeout=10)
    assert monitor.returncode == 130, err
    lines = out.splitlines()
    text = "\n".join(lines)
    assert any("] plan (" in line for line in lines), text
    for record in report.result.actions:
        assert f"EXECUTING {record.text}" in text
        assert f"ASSIGNED  {record.text} -> {record.performer} (1 bid)" in text
        assert f"SUCCEEDED {record.text}" in text
    assert "performer r1_base: READY" in text and "performer r2_base: READY" in text
    assert "knowledge: 5 instances, " in text and "goal (and (visited r1 kitchen)" in text
    assert "Traceback" not in err
