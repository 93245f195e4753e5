"""Performers in a subprocess, executor in the test process: one mission over DDS."""

from __future__ import annotations

import asyncio
import signal
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from dds_missions import performers_in_subprocess, read_line, write_mission

from plansys_bridge.cli import main
from plansys_bridge.errors import ConfigError, HubError
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import run_mission
from plansys_bridge.mission_config import load_mission

pytestmark = pytest.mark.timeout(90)


@pytest.fixture
def performers_process(tmp_path: Path) -> Iterator[tuple[Path, subprocess.Popen[str]]]:
    mission = write_mission(tmp_path)
    with performers_in_subprocess(mission) as proc:
        yield mission, proc


def test_executor_here_performers_in_a_subprocess(
    performers_process: tuple[Path, subprocess.Popen[str]],
) -> None:
    mission_path, proc = performers_process
    ready = read_line(proc, timeout=30)
    assert ready.startswith("performers ready: r1_base, r2_base"), ready

    lines: list[str] = []
    report = run_mission(load_mission(mission_path), out=lines.append, local_performers=False)

    assert report.success, "\n".join(lines)
    assert report.result is not None
    records = report.result.actions
    assert len(records) == 3
    assert all(a.status == ActionStatus.SUCCEEDED for a in records)
    # Every action was done by the performer in the other process that serves its robot.
    assert {(a.text.split()[1], a.performer) for a in records} == {
        ("r1", "r1_base"),
        ("r2", "r2_base"),
    }
    assert any("2 remote performers" in line for line in lines)

    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=15)
    assert proc.returncode == 0, err
    assert "performers stopped" in out


def test_the_executor_names_performers_that_never_show_up(tmp_path: Path) -> None:
    mission = load_mission(write_mission(tmp_path, peer_timeout=0.5))
    with pytest.raises(HubError, match=r"no heartbeat from performer\(s\) r1_base, r2_base"):
        run_mission(mission, out=None, local_performers=False)


def test_split_runs_need_the_dds_transport(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "inprocess.yaml"
    text = write_mission(tmp_path).read_text(encoding="utf-8")
    path.write_text(
        text.replace(
            text[text.index("transport:") :].split("\n")[0], "transport: {kind: inprocess}"
        ),
        encoding="utf-8",
    )
    with pytest.raises(ConfigError, match="transport"):
        run_mission(load_mission(path), out=None, local_performers=False)
    assert main(["performers", str(path)]) == 2
    assert "need a transport between processes (transport: {kind: dds})" in capsys.readouterr().err


def test_dds_with_the_virtual_clock_is_refused_on_load(tmp_path: Path) -> None:
    path = write_mission(tmp_path)
    path.write_text(
        path.read_text(encoding="utf-8").replace(
            "clock: {kind: wall, time_scale: 0.2}", "clock: {kind: virtual}"
        ),
        encoding="utf-8",
    )
    with pytest.raises(ConfigError, match="dds transport needs the wall clock"):
        load_mission(path)


def test_dds_settings_belong_to_the_dds_transport(tmp_path: Path) -> None:
    path = write_mission(tmp_path)
    text = path.read_text(encoding="utf-8")
    line = text[text.index("transport:") :].split("\n")[0]
    path.write_text(text.replace(line, "transport: {kind: inprocess, domain_id: 3}"), "utf-8")
    with pytest.raises(ConfigError, match="domain_id applies to the dds transport only"):
        load_mission(path)
    path.write_text(text.replace(line, "transport: {kind: dds, domain_id: 233}"), "utf-8")
    with pytest.raises(ConfigError, match=r"transport\.domain_id"):
        load_mission(path)


def test_a_killed_performer_process_fails_the_action_instead_of_hanging(tmp_path: Path) -> None:
    """PlanSys2 leaves the action RUNNING forever (#399); here liveness catches it."""
    path = write_mission(tmp_path)
    text = path.read_text(encoding="utf-8").replace(
        "default_duration: 1.0", "default_duration: 50.0"
    )
    path.write_text(
        text
        + "auction: {liveness_timeout: 1.0, reauctions: 0, give_up_after: 2.0}\n"
        + "replanning: {max_replans: 0}\n",
        encoding="utf-8",
    )
    lines: list[str] = []
    with performers_in_subprocess(path) as proc:
        assert read_line(proc, timeout=30).startswith("performers ready")

        def kill_when_executing(line: str) -> None:
            lines.append(line)
            if "EXECUTING" in line and not lines_killed:
                # Half a second into the 10 s actions, long after CONFIRM: the process
                # vanishes without a goodbye (no FINISH, no heartbeat).
                lines_killed.append(asyncio.get_running_loop().call_later(0.5, proc.kill))

        lines_killed: list[asyncio.TimerHandle] = []

        report = run_mission(load_mission(path), out=kill_when_executing, local_performers=False)
    assert not report.success
    assert report.result is not None
    failed = [a for a in report.result.actions if a.status == ActionStatus.FAILED]
    assert failed, "\n".join(lines)
    assert any("performer r1_base lost" in line for line in lines), "\n".join(lines)
