"""The terminal's ``run`` and ``check actors`` with PlanSys2's semantics, on the real
executor with simulated performers on the virtual clock.

``run`` aims at the goal (replanning on failure); ``run action``, ``run num_actions``
and ``run plan-file`` execute exactly what was asked and stop there.
"""

from __future__ import annotations

import argparse
import io
import re
from pathlib import Path

import pytest

from plansys_bridge.cli import terminal_cmd
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.mission import build_knowledge
from plansys_bridge.mission_config import load_mission
from plansys_bridge.terminal import Terminal
from plansys_bridge.terminal.mission_runner import MissionRunner

SIMPLE_DOMAIN = Path(__file__).parent / "data" / "simple_example.pddl"

MISSION = """
name: terminal_run
domain: {domain}
knowledge:
  instances: {{leia: robot, entrance: room, dinning: room, kitchen: room, chargingroom: room}}
  predicates:
    - (connected entrance dinning)
    - (connected dinning kitchen)
    - (connected kitchen chargingroom)
    - (connected chargingroom kitchen)
    - (charging_point_at chargingroom)
    - (battery_low leia)
    - (robot_at leia entrance)
goal: (and (robot_at leia kitchen))
performers:
  - kind: simulated
    name: leia_base
    actions: {{move: [leia], askcharge: [leia], charge: [leia]}}
    durations: {{move: 5, askcharge: 5, charge: 5}}
    success_rate: {success}
clock: {{kind: virtual}}
"""


def _terminal(
    tmp_path: Path, success: float = 1.0, console: object = None
) -> tuple[Terminal, io.StringIO]:
    file = tmp_path / "mission.yaml"
    file.write_text(MISSION.format(domain=SIMPLE_DOMAIN, success=success))
    mission = load_mission(file)
    knowledge = build_knowledge(mission, DomainExpert.from_files(list(mission.domain_paths)).domain)
    out = io.StringIO()
    runner = MissionRunner(
        mission,
        knowledge,
        _planner,
        out=lambda line: out.write(line + "\n"),
        live=console is not None,
        console=console,
    )
    term = Terminal(knowledge.domain_expert, knowledge, runner=runner, base_dir=tmp_path)
    return term, out


def _planner() -> object:
    from plansys_bridge.planning.planner import Planner

    return Planner()


def _charged(term: Terminal) -> None:
    assert term.execute_line("remove predicate (battery_low leia)") == ""
    assert term.execute_line("set predicate (battery_full leia)") == ""


def _facts(term: Terminal) -> set[str]:
    return {str(a) for a in term.problem_expert.get_predicates()}


def _executed(text: str) -> list[str]:
    """The action lines of a run's outcome (``  SUCCEEDED (a x)``)."""
    return re.findall(r"^  (\w+)\s+(\(.*\))$", text, flags=re.MULTILINE)  # type: ignore[return-value]


def test_run_action_runs_exactly_that_action_and_stops(tmp_path: Path) -> None:
    term, progress = _terminal(tmp_path)
    _charged(term)
    out = term.execute_line("run action (move leia entrance dinning)")
    assert out.splitlines()[0] == "succeeded"
    assert _executed(out) == [("SUCCEEDED", "(move leia entrance dinning)")]
    facts = _facts(term)
    # the goal (leia in the kitchen) was not pursued: leia stopped in the dining room
    assert "(robot_at leia dinning)" in facts and "(robot_at leia kitchen)" not in facts
    assert "EXECUTING (move leia entrance dinning)" in progress.getvalue()
    assert "ASSIGNED  (move leia entrance dinning) -> leia_base (1 bid)" in progress.getvalue()
    # the short form, checked against the knowledge: leia is no longer at the entrance
    out = term.execute_line("run (move leia entrance dinning)")
    assert out.startswith("error: execution rejected: ") and "(robot_at leia entrance)" in out
    assert _facts(term) == facts
    unknown = term.execute_line("run action (move leia dinning nowhere)")
    assert unknown.startswith("error: ") and "nowhere" in unknown


def test_run_num_actions_runs_the_first_actions_of_the_plan(tmp_path: Path) -> None:
    term, _ = _terminal(tmp_path)
    plan = term.execute_line("get plan").splitlines()
    assert len(plan) == 3
    out = term.execute_line("run num_actions 2")
    assert _executed(out) == [
        ("SUCCEEDED", "(askcharge leia entrance chargingroom)"),
        ("SUCCEEDED", "(charge leia chargingroom)"),
    ]
    facts = _facts(term)
    assert "(battery_full leia)" in facts and "(robot_at leia chargingroom)" in facts
    assert "(robot_at leia kitchen)" not in facts
    too_many = term.execute_line("run num_actions 99")
    assert too_many.startswith("error: cannot execute 99 actions: the plan has ")
    assert term.execute_line("run num_actions 0").startswith("error: cannot execute 0 actions")
    assert _facts(term) == facts


def test_run_plan_file_runs_exactly_that_plan(tmp_path: Path) -> None:
    term, _ = _terminal(tmp_path)
    _charged(term)
    (tmp_path / "plan.txt").write_text(
        "0.000: (move leia entrance dinning)  [5.000]\n"
        "5.001: (move leia dinning kitchen)  [5.000]\n"
    )
    out = term.execute_line("run plan-file plan.txt")
    assert out.splitlines()[0] == "succeeded"
    assert [text for _, text in _executed(out)] == [
        "(move leia entrance dinning)",
        "(move leia dinning kitchen)",
    ]
    assert "(robot_at leia kitchen)" in _facts(term)


def test_run_reaches_the_goal(tmp_path: Path) -> None:
    term, progress = _terminal(tmp_path)
    out = term.execute_line("run")
    assert out.splitlines()[0] == "succeeded"
    assert _executed(out)[-1] == ("SUCCEEDED", "(move leia chargingroom kitchen)")
    assert "(robot_at leia kitchen)" in _facts(term)
    assert "SUCCEEDED (askcharge leia entrance chargingroom)" in progress.getvalue()


def test_a_failed_action_is_not_replanned_outside_run(tmp_path: Path) -> None:
    term, progress = _terminal(tmp_path, success=0.0)
    _charged(term)
    before = _facts(term)
    out = term.execute_line("run action (move leia entrance dinning)")
    assert out.startswith("error: execution failed: ")
    assert _executed(out) == [("FAILED", "(move leia entrance dinning)")]
    assert "replanned" not in progress.getvalue()
    assert _facts(term) == before
    # a bare run replans after each failure, up to the mission's budget
    out = term.execute_line("run")
    assert out.startswith("error: execution failed: ") and "replanning budget" in out
    assert "replanned (plan 2, " in progress.getvalue()


def test_check_actors_lists_live_heartbeats(tmp_path: Path) -> None:
    term, _ = _terminal(tmp_path)
    out = term.execute_line("check actors")
    lines = out.splitlines()
    assert lines[0] == "Actors: 1"
    assert re.fullmatch(
        r"\t\[leia_base\] askcharge \[leia\], charge \[leia\], move \[leia\]"
        r"\tREADY\tlast seen [01]\.\d s ago",
        lines[1],
    ), lines[1]


@pytest.mark.parametrize("echo", ["0", "1"])
def test_source_with_echo_flag(tmp_path: Path, echo: str) -> None:
    term, _ = _terminal(tmp_path)
    (tmp_path / "cmds").write_text("set instance bedroom room\nget problem goal\n")
    out = term.execute_line(f"source cmds {echo}")
    goal = "Goal: (and (robot_at leia kitchen))"
    expected = f"> set instance bedroom room\n> get problem goal\n{goal}" if echo == "1" else goal
    assert out == expected
    assert term.execute_line("source cmds 2").startswith("error: usage: source FILE [0|1]")


def _cli_args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    terminal_cmd.register(parser.add_subparsers())
    return parser.parse_args(["terminal", *argv])


def test_cli_mission_runs_plans_with_its_performers(tmp_path: Path) -> None:
    """``--mission``: the real executor and simulated performers on the virtual clock."""
    mission = tmp_path / "mission.yaml"
    mission.write_text(MISSION.format(domain=SIMPLE_DOMAIN, success=1.0))
    out = io.StringIO()
    commands = "check actors\nrun\nget problem predicates\nrun action (move leia kitchen dinning)\n"
    code = terminal_cmd.run(_cli_args("--mission", str(mission)), io.StringIO(commands), out)
    text = out.getvalue()
    assert code == 1, text  # the last action has no (connected kitchen dinning)
    assert "Actors: 1\n\t[leia_base] askcharge [leia], charge [leia], move [leia]\tREADY" in text
    assert "succeeded\n  SUCCEEDED (askcharge leia entrance chargingroom)" in text
    assert "(robot_at leia kitchen)" in text and "(battery_full leia)" in text
    last = text.split("(robot_at leia kitchen)\n")[-1]
    assert last.startswith("error: execution rejected: ")
    assert "(move leia kitchen dinning)" in last and "(connected kitchen dinning)" in last


def test_plain_progress_shows_completion_from_feedback(tmp_path: Path) -> None:
    """Not a terminal: one line per change, and completion at each quarter."""
    term, progress = _terminal(tmp_path)
    _charged(term)
    assert term.execute_line("run action (move leia entrance dinning)").startswith("succeeded")
    lines = progress.getvalue().splitlines()
    quarters = [line.split("] ", 1)[1] for line in lines if "PROGRESS" in line]
    assert quarters == [
        f"PROGRESS  (move leia entrance dinning) {pct} % (leia_base)" for pct in (25, 50, 75)
    ]
    executing = next(i for i, line in enumerate(lines) if "EXECUTING" in line)
    succeeded = next(i for i, line in enumerate(lines) if "SUCCEEDED" in line)
    assert executing < min(i for i, line in enumerate(lines) if "PROGRESS" in line) < succeeded


def test_live_table_on_a_terminal(tmp_path: Path) -> None:
    """On a terminal: the live table (state, completion, performer; performers under
    it), failures and replans printed above it, no per-change lines."""
    rich_console = pytest.importorskip("rich.console", reason="the ui extra (rich) is missing")
    screen = io.StringIO()
    console = rich_console.Console(file=screen, force_terminal=True, width=160, color_system=None)
    term, progress = _terminal(tmp_path, success=0.0, console=console)
    out = term.execute_line("run")
    assert out.startswith("error: execution failed: ")
    assert progress.getvalue() == ""
    drawn = screen.getvalue()
    assert "terminal_run  t=" in drawn and "plan 1 (3 actions)" in drawn
    assert "(askcharge leia entrance chargingroom)" in drawn and "leia_base" in drawn
    assert "│ failed " in drawn
    assert "performers  leia_base: " in drawn
    assert "FAILED    (askcharge leia entrance chargingroom)" in drawn
    assert "replanned (plan 2, " in drawn
    # a succeeding run ends with the whole plan drawn done
    screen = io.StringIO()
    console = rich_console.Console(file=screen, force_terminal=True, width=160, color_system=None)
    term, _ = _terminal(tmp_path, console=console)
    assert term.execute_line("run").startswith("succeeded")
    final = screen.getvalue()
    final = final[final.rindex("plan 1 (3 actions)") :]
    assert final.count("100 %") == 3 and final.count("succeeded") == 3


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_cli_draws_the_live_table_when_its_output_is_a_terminal(tmp_path: Path) -> None:
    pytest.importorskip("rich.console", reason="the ui extra (rich) is missing")
    mission = tmp_path / "mission.yaml"
    mission.write_text(MISSION.format(domain=SIMPLE_DOMAIN, success=1.0))
    screen = _Tty()
    code = terminal_cmd.run(_cli_args("--mission", str(mission)), io.StringIO("run\n"), screen)
    text = screen.getvalue()
    assert code == 0, text
    assert "terminal_run  t=" in text and "100 %" in text
    assert "EXECUTING (" not in text  # the table, not the plain lines
    assert "succeeded\n  SUCCEEDED (askcharge leia entrance chargingroom)" in text


def test_cli_no_performers_needs_a_dds_mission(tmp_path: Path) -> None:
    from plansys_bridge.errors import ConfigError

    mission = tmp_path / "mission.yaml"
    mission.write_text(MISSION.format(domain=SIMPLE_DOMAIN, success=1.0))
    with pytest.raises(ConfigError, match=r"transport.kind.*need a transport between processes"):
        terminal_cmd.run(
            _cli_args("--mission", str(mission), "--no-performers"), io.StringIO(""), io.StringIO()
        )
    assert (
        terminal_cmd.run(
            _cli_args("--no-performers", str(SIMPLE_DOMAIN)), io.StringIO(""), io.StringIO()
        )
        == 2
    )
