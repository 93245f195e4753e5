"""Pictures and summary of a run: the demo mission (real executor, simulated
performers, virtual clock, a replan) drawn live and from its recording."""

from __future__ import annotations

import json
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from plansys_bridge.cli import main
from plansys_bridge.hub.messages import ActionStatus
from plansys_bridge.mission import MissionReport, run_mission
from plansys_bridge.mission_config import load_mission
from plansys_bridge.report.graph import render_dot
from plansys_bridge.report.model import RunReport
from plansys_bridge.report.write import write_report

pytest.importorskip("matplotlib", reason="the report extra (matplotlib) is not installed")
pytest.importorskip("pydot", reason="the report extra (pydot) is not installed")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SVG = "{http://www.w3.org/2000/svg}"


def _demo(record: Path | None = None) -> MissionReport:
    mission = load_mission(CONFIGS / "demo_cooking.yaml")
    update: dict[str, object] = {"clock": mission.clock.model_copy(update={"kind": "virtual"})}
    if record is not None:
        update["record"] = str(record)
    return run_mission(mission.model_copy(update=update), out=None)


def _svg_texts(path: Path) -> list[str]:
    root = ET.parse(path).getroot()  # well-formed SVG, or this raises
    assert root.tag == f"{SVG}svg"
    return ["".join(t.itertext()).strip() for t in root.iter(f"{SVG}text")]


@pytest.fixture(scope="module")
def demo() -> MissionReport:
    report = _demo()
    assert report.success and report.result is not None and report.result.replans == 1
    return report


def _run_report(report: MissionReport) -> RunReport:
    assert report.watch is not None and report.result is not None
    return RunReport.from_watch(
        report.watch,
        name=report.name,
        status=report.status,
        success=report.success,
        started=report.result.started,
        finished=report.result.finished,
    )


def test_report_files_of_a_replanned_run(demo: MissionReport, tmp_path: Path) -> None:
    result = demo.result
    assert result is not None
    files = write_report(_run_report(demo), tmp_path, use_graphviz=False)
    names = sorted(p.name for p in files)
    assert names == [
        "gantt.png",
        "gantt.svg",
        "plan_graph.dot",
        "plan_graph.svg",
        "plan_graph_1.dot",
        "plan_graph_1.svg",
        "summary.json",
    ]
    assert (tmp_path / "gantt.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    gantt = _svg_texts(tmp_path / "gantt.svg")
    performers = sorted({a.performer for a in result.actions if a.performer})
    assert set(performers) <= set(gantt)  # one row per performer
    assert "replan: plan 2" in gantt and "not executed" in gantt
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "succeeded" and summary["replans"] == 1
    assert summary["plans"] == len(result.plans) == 2
    assert summary["actions"] == len(result.actions)
    statuses = {s.name: 0 for s in ActionStatus}
    for a in result.actions:
        statuses[a.status.name] += 1
    assert summary["actions_by_status"] == {k: v for k, v in statuses.items() if v}
    # same metric as the executor's (it counts from the confirm, the report from the
    # EXECUTING status: the same instant on the in-process hub)
    assert summary["efficiency_percent"] == pytest.approx(result.efficiency_percent, abs=0.5)
    assert summary["plan_graph_layout"] == "python"
    assert summary["replan_times_s"][0] == pytest.approx(
        next(a.end for a in result.actions if a.status == ActionStatus.FAILED) or 0.0, abs=7.0
    )
    # the last plan's graph: every action with its state, a line break in DOT's escape
    dot = (tmp_path / "plan_graph.dot").read_text()
    assert "recharge_zone)\\n[" in dot and "\\\\n" not in dot
    graph = _svg_texts(tmp_path / "plan_graph.svg")
    last_plan = [a.text for a in result.actions if a.plan_index == 1]
    for text in last_plan:
        assert any(text in label for label in graph), text
    assert all("\\n" not in label for label in graph)


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz (dot) is not installed")
def test_plan_graph_with_graphviz(demo: MissionReport, tmp_path: Path) -> None:
    text = next(iter(_run_report(demo).dots.values()))
    assert render_dot(text, tmp_path / "g.svg") == "graphviz"
    texts = _svg_texts(tmp_path / "g.svg")
    assert any("(move robot1" in t for t in texts)
    # each action's label on two lines: its text, then its times and state
    assert any(re.fullmatch(r"\[\d+\.\d{3}, \d+\.\d{3}\] succeeded", t) for t in texts)
    assert not any("\\" in t for t in texts)


def test_report_of_a_recording_matches_the_live_one(
    demo: MissionReport, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    recorded = _demo(record=tmp_path / "bag")
    assert recorded.success
    live = write_report(_run_report(recorded), tmp_path / "live", use_graphviz=False)
    assert main(["report", str(tmp_path / "bag"), "--out", str(tmp_path / "rec")]) == 0
    printed = capsys.readouterr().out.split()
    assert str(tmp_path / "rec" / "gantt.svg") in printed
    live_summary = json.loads(next(p for p in live if p.name == "summary.json").read_text())
    rec_summary = json.loads((tmp_path / "rec" / "summary.json").read_text())
    for key in ("plans", "replans", "actions", "actions_by_status", "success", "plan_texts"):
        assert rec_summary[key] == live_summary[key], key
    assert rec_summary["performer_busy_s"].keys() == live_summary["performer_busy_s"].keys()
    assert rec_summary["total_time_s"] == pytest.approx(live_summary["total_time_s"], abs=0.1)
    for name in ("gantt.png", "plan_graph.svg", "plan_graph_1.dot"):
        assert (tmp_path / "rec" / name).stat().st_size > 0


def test_report_of_something_that_is_not_a_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["report", str(tmp_path / "nope"), "--out", str(tmp_path / "out")]) == 2
    assert "no such recording" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["report", str(tmp_path / "empty"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and str(tmp_path / "empty") in err


def test_run_command_writes_the_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        [
            "run",
            str(CONFIGS / "demo_cooking.yaml"),
            "--clock",
            "virtual",
            "--report",
            str(tmp_path / "r"),
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert f"wrote {tmp_path / 'r' / 'summary.json'}" in out
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["success"] is True
