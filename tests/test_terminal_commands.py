"""Terminal commands PlanSys2's newer terminal has: ``?``/``help CMD``, derived
predicates, and the tab completion of commands, names and objects."""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.knowledge.domain_expert import DomainExpert
from plansys_bridge.knowledge.problem_expert import ProblemExpert
from plansys_bridge.terminal import HELP, Terminal
from plansys_bridge.terminal.completion import candidates

DATA = Path(__file__).parent / "data"


def _terminal(domain: str) -> Terminal:
    de = DomainExpert.from_files([DATA / domain])
    return Terminal(de, ProblemExpert(de))


def test_help_and_question_mark() -> None:
    term = _terminal("simple_example.pddl")
    assert term.execute_line("?") == HELP == term.execute_line("help")
    run_help = term.execute_line("? run")
    assert "run num_actions N" in run_help and "run plan-file FILE" in run_help
    assert "get model" not in run_help
    assert term.execute_line("help source").strip().startswith("source FILE [0|1]")
    assert term.execute_line("help fly").startswith("error: no command 'fly'")


def test_get_model_deriveds() -> None:
    term = _terminal("domain_simple_derived.pddl")
    assert term.execute_line("get model deriveds") == (
        "Derived predicates: 2\n"
        "\t(inferred-robot_at ?r - robot ?ro - room)\n"
        "\t(inferred-person_at ?p - person ?ro - room)"
    )
    assert term.execute_line("get model derived inferred-robot_at") == (
        "Parameters: 2\n\t?r - robot\n\t?ro - room\nPreconditions: (and (robot_at ?r ?ro))"
    )
    assert term.execute_line("get model derived robot_at") == (
        "error: no derived predicate 'robot_at'"
    )
    assert "(derived)" in term.execute_line("get model predicate inferred-robot_at")


def test_completion_of_commands_names_and_objects() -> None:
    term = _terminal("simple_example.pddl")
    for line in ("set instance leia robot", "set instance kitchen room", "set instance kid room"):
        assert term.execute_line(line) == ""
    k = term.problem_expert
    assert candidates("", k) == sorted(
        ["get", "set", "remove", "run", "check", "source", "help", "?", "quit"]
    )
    assert candidates("ru", k) == ["run"]
    assert candidates("run ", k) == ["action", "num_actions", "plan-file"]
    assert candidates("get model d", k) == ["derived", "deriveds"]
    assert candidates("get problem i", k) == ["instances"]
    assert candidates("set predicate (robot", k) == ["robot_at"]
    assert candidates("set predicate (robot_at l", k) == ["leia"]
    assert candidates("set predicate (robot_at leia k", k) == ["kid", "kitchen"]
    assert candidates("run action (mo", k) == ["move"]
    assert candidates("run (move leia ", k) == ["kid", "kitchen", "leia"]
    assert candidates("set instance bedroom ", k) == ["robot", "room"]
    assert candidates("remove instance k", k) == ["kid", "kitchen"]
    assert candidates("get model action a", k) == ["askcharge"]
    assert candidates("check ", k) == ["actors"]
    assert candidates("quit now ", k) == []


def test_history_is_kept_between_sessions(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    readline = pytest.importorskip("readline", reason="no readline on this platform")
    from plansys_bridge.terminal import repl

    monkeypatch.setattr(repl, "HISTORY_FILE", tmp_path / "history")
    readline.clear_history()
    first = repl._History()
    first.load()  # no file yet: nothing, and no error
    readline.add_history("get problem goal")
    readline.add_history("run num_actions 2")
    first.save()
    readline.clear_history()
    repl._History().load()
    lines = [
        readline.get_history_item(i) for i in range(1, readline.get_current_history_length() + 1)
    ]
    assert lines == ["get problem goal", "run num_actions 2"]
    assert readline.get_history_length() == repl.HISTORY_LENGTH
    readline.clear_history()
