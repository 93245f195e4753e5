"""The terminal: PlanSys2's command files, every command, errors that never end it."""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import pytest
from pddl_corpus import FIXTURES

from plansys_bridge.cli import terminal_cmd
from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.terminal import HELP, Terminal

EXAMPLES = FIXTURES / "ros2_planning_system_examples"
SIMPLE_DOMAIN = EXAMPLES / "plansys2_simple_example/pddl/simple_example.pddl"
BT_DOMAIN = EXAMPLES / "plansys2_bt_example/pddl/bt_example.pddl"

# (commands file, domain files, instances, facts after sourcing without `run`/`get`,
# object the file uses without declaring it)
COMMAND_FILES = [
    (EXAMPLES / "plansys2_simple_example/launch/commands", [SIMPLE_DOMAIN], 7, 13, None),
    (
        EXAMPLES / "plansys2_simple_example_py/launch/commands",
        [EXAMPLES / "plansys2_simple_example_py/pddl/simple_example.pddl"],
        7,
        13,
        None,
    ),
    # it places r2d2 before declaring it (the cooking copy below declares it first)
    (EXAMPLES / "plansys2_bt_example/launch/commands", [BT_DOMAIN], 18, 20, "r2d2"),
    (
        EXAMPLES / "plansys2_cascade_example/launch/commands",
        [EXAMPLES / "plansys2_cascade_example/pddl/cascade_example.pddl"],
        7,
        13,
        None,
    ),
    (
        EXAMPLES / "plansys2_multidomain_example/launch/commands",
        [
            EXAMPLES / "plansys2_multidomain_example/pddl_1/domain_1.pddl",
            EXAMPLES / "plansys2_multidomain_example/pddl_2/domain_2.pddl",
        ],
        8,
        14,
        None,
    ),
    # the cooking experiment ships the factory commands of the bt example
    (FIXTURES / "plansys2_cooking_experiment/launch/commands", [BT_DOMAIN], 18, 22, None),
]


def make_terminal(domains: list[Path], **kwargs: object) -> Terminal:
    de = DomainExpert.from_files(domains)
    return Terminal(de, ProblemExpert(de), **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("commands", "domains", "instances", "facts", "undeclared"),
    COMMAND_FILES,
    ids=[c[0].parent.parent.name for c in COMMAND_FILES],
)
def test_source_plansys2_command_files(
    commands: Path, domains: list[Path], instances: int, facts: int, undeclared: str | None
) -> None:
    term = make_terminal(domains)
    output = term.source(commands, skip={"run", "get"})
    errors = [line for line in output.splitlines() if "error: " in line]
    if undeclared is None:
        assert errors == []
    else:
        assert errors and all(f"unknown object {undeclared!r}" in e for e in errors)
    pe = term.problem_expert
    assert len(pe.get_instances()) == instances
    assert len(pe.get_predicates()) == facts
    assert pe.get_goal() is not None


def test_get_model_commands() -> None:
    term = make_terminal([SIMPLE_DOMAIN])
    assert term.execute_line("get model types") == "Types: 2\n\trobot\n\troom"
    predicates = term.execute_line("get model predicates")
    assert predicates.startswith("Predicates: 5\n")
    assert "\t(robot_at ?r - robot ?ro - room)" in predicates
    assert term.execute_line("get model predicate ROBOT_AT") == (
        "Predicate robot_at parameters: 2\n\t?r - robot\n\t?ro - room"
    )
    assert "move (durative action)" in term.execute_line("get model actions")
    action = term.execute_line("get model action move")
    assert "Duration: (= ?duration 5)" in action
    assert "At end effect: (robot_at ?r ?r2)" in action
    assert term.execute_line("get model functions").startswith("Functions: ")
    assert term.execute_line("get model action fly") == "error: unknown action 'fly'"
    assert term.execute_line("get model predicate nope").startswith("error: unknown predicate")
    assert term.execute_line("get model colours").startswith("error: usage: get model")
    assert term.execute_line("get domain").lstrip().startswith("(define (domain")


def test_set_get_remove_problem() -> None:
    term = make_terminal([SIMPLE_DOMAIN])
    run = term.execute_line
    assert run("set instance leia robot") == ""
    assert run("set instance leia robot") == "instance leia already exists"
    assert run("set instance kitchen room") == ""
    assert run("set instance bedroom room") == ""
    assert run("set predicate (robot_at leia kitchen)") == ""
    assert run("set predicate robot_at leia bedroom") == ""  # PlanSys2's old form
    assert run("set predicate (robot_at leia kitchen)") == "(robot_at leia kitchen) already holds"
    assert run("set goal (and (robot_at leia bedroom))") == ""
    assert (
        run("get problem instances")
        == "Instances: 3\n\tleia\trobot\n\tkitchen\troom\n\tbedroom\troom"
    )
    assert run("get problem predicates") == (
        "Predicates: 2\n(robot_at leia kitchen)\n(robot_at leia bedroom)"
    )
    assert run("get problem goal") == "Goal: (and (robot_at leia bedroom))"
    assert run("remove predicate battery_full leia") == "(battery_full leia) does not hold"
    assert run("remove predicate (robot_at leia kitchen)") == ""
    assert run("remove goal") == ""
    assert run("get problem goal") == "Goal: (none)"
    assert run("remove instance bedroom") == ""
    assert run("get problem predicates") == "Predicates: 0"
    assert run("remove instance bedroom") == "no instance bedroom"
    text = run("get problem")
    assert "(:objects" in text and "leia - robot" in text


def test_functions_on_a_numeric_domain() -> None:
    de = DomainExpert.from_files(
        [FIXTURES / "ros2_planning_system/plansys2_problem_expert/test/pddl/domain_charging.pddl"]
    )
    term = Terminal(de, ProblemExpert(de))
    for line in (
        "set instance r2d2 robot",
        "set instance wp1 waypoint",
        "set instance wp2 waypoint",
    ):
        assert term.execute_line(line) == ""
    assert term.execute_line("set function (= (distance wp1 wp2) 15)") == ""
    assert term.execute_line("set function (= (speed r2d2) 2.5)") == ""
    assert term.execute_line("get problem functions") == (
        "Functions: 2\n(= (distance wp1 wp2) 15)\n(= (speed r2d2) 2.5)"
    )
    assert term.execute_line("remove function (distance wp1 wp2)") == ""
    assert term.execute_line("remove function (distance wp1 wp2)") == (
        "function (distance wp1 wp2) has no value"
    )
    assert term.execute_line("set function (= (speed wp1) 3)").startswith("error: ")


def test_errors_are_reported_and_change_nothing() -> None:
    term = make_terminal([SIMPLE_DOMAIN])
    state = term.problem_expert.state()
    for line in (
        "set instance leia spaceship",
        "set instance leia",
        "set predicate (robot_at leia nowhere)",
        "set predicate (flying leia",
        "set goal (and (robot_at leia nowhere))",
        "set goal",
        "set colour red",
        "remove nothing",
        "frobnicate",
        "run num_actions x",
        "source /nonexistent/commands",
        "check everything",
    ):
        out = term.execute_line(line)
        assert out.startswith("error: "), (line, out)
    assert term.problem_expert.state() == state and term.problem_expert.version == 0
    term.execute_line("set instance leia robot")
    located = term.execute_line("set predicate (robot_at leia nowhere)")
    assert "unknown object 'nowhere'" in located and "^" in located
    assert term.execute_line("") == "" and term.execute_line("# comment") == ""
    assert term.execute_line("help") == HELP


def test_internal_errors_do_not_end_the_session() -> None:
    def broken_planner() -> object:
        raise ZeroDivisionError("division by zero")

    term = make_terminal([SIMPLE_DOMAIN], planner_factory=broken_planner)
    term.source(EXAMPLES / "plansys2_simple_example/launch/commands", skip={"run"})
    assert term.execute_line("get plan") == "internal error: ZeroDivisionError: division by zero"
    assert term.execute_line("get problem goal") == "Goal: (and (robot_at leia bathroom))"


def test_run_without_executor_says_so() -> None:
    term = make_terminal([SIMPLE_DOMAIN])
    assert "no executor is configured" in term.execute_line("run")
    assert "no hub is connected" in term.execute_line("check actors")


def test_source_nested_relative_and_recursive(tmp_path: Path) -> None:
    (tmp_path / "inner").write_text(
        "set instance kitchen room\nset predicate (robot_at leia kitchen)\n"
    )
    (tmp_path / "outer").write_text(
        "set instance leia robot\nsource inner\nget problem predicates\n"
    )
    (tmp_path / "loop").write_text("source loop\n")
    term = make_terminal([SIMPLE_DOMAIN], base_dir=tmp_path)
    assert term.execute_line("source outer") == "Predicates: 1\n(robot_at leia kitchen)"
    assert "sourced recursively" in term.execute_line("source loop")
    bad = tmp_path / "bad"
    bad.write_text("set instance x robot\n\nset predicate (robot_at x moon)\n")
    assert term.execute_line(f"source {bad}").startswith(f"{bad}:3: error: ")


def test_repl_reads_until_quit() -> None:
    out = io.StringIO()
    term = make_terminal([SIMPLE_DOMAIN], out=out)
    commands = io.StringIO(
        "set instance leia robot\nbogus\nget problem instances\nquit\nset instance r2 robot\n"
    )
    assert term.repl(commands) == 0
    text = out.getvalue()
    assert "error: unknown command 'bogus'" in text
    assert "Instances: 1\n\tleia\trobot\n" in text
    assert not term.problem_expert.exist_instance("r2")  # after quit nothing more is read
    assert ">" not in text  # no prompt when the input is not a terminal


def _cli_args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    terminal_cmd.register(parser.add_subparsers())
    return parser.parse_args(["terminal", *argv])


def test_cli_sources_then_reads_stdin() -> None:
    out = io.StringIO()
    args = _cli_args(
        str(SIMPLE_DOMAIN), "--source", str(EXAMPLES / "plansys2_simple_example/launch/commands")
    )
    code = terminal_cmd.run(args, stdin=io.StringIO("get problem goal\n"), stdout=out)
    assert code == 0
    assert "Goal: (and (robot_at leia bathroom))" in out.getvalue()
    out = io.StringIO()
    code = terminal_cmd.run(args, stdin=io.StringIO("run\nget problem goal\n"), stdout=out)
    assert code == 1  # `run` failed: no executor; the session went on
    assert "no executor" in out.getvalue() and "Goal: (and" in out.getvalue()

    out = io.StringIO()
    problem = (
        FIXTURES / "ros2_planning_system/plansys2_problem_expert/test/pddl/problem_simple_1.pddl"
    )
    domain = FIXTURES / "ros2_planning_system/plansys2_problem_expert/test/pddl/domain_simple.pddl"
    args = _cli_args(str(domain), "--problem", str(problem))
    assert terminal_cmd.run(args, stdin=io.StringIO("get problem predicates\n"), stdout=out) == 0
    assert "(robot_at leia kitchen)" in out.getvalue()


def test_cli_needs_domain_or_mission(tmp_path: Path) -> None:
    assert terminal_cmd.run(_cli_args(), io.StringIO(""), io.StringIO()) == 2
    missing = _cli_args(str(SIMPLE_DOMAIN), "--problem", str(tmp_path / "nope.pddl"))
    assert terminal_cmd.run(missing, io.StringIO(""), io.StringIO()) == 2
