"""The command line given bad input: one clear line naming the place, a non-zero exit.

Each case is what an engineer at a robot gets wrong: a binary file where a text file
belongs, a directory, a missing file, a typo in a mission file, a nonsense number.
The answer is always ``error: <place>: <reason>`` on stderr and exit status 2, never
a traceback.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from plansys_bridge.cli import main

ROOT = Path(__file__).resolve().parents[2]
DOMAIN = str(ROOT / "configs" / "pddl" / "flat_navigation.pddl")

PROBLEM = """\
(define (problem p) (:domain flat_navigation)
  (:objects tiago - robot kitchen hall - room)
  (:init (robot_at tiago kitchen) (connected kitchen hall) (= (travel_time kitchen hall) 5))
  (:goal (and (visited tiago hall))))
"""

MISSION = f"""\
name: qa
domain: {DOMAIN}
knowledge:
  instances: {{tiago: robot, kitchen: room, hall: room}}
  predicates: ["(robot_at tiago kitchen)", "(connected kitchen hall)"]
  functions: ["(= (travel_time kitchen hall) 5)"]
goal: (visited tiago hall)
performers:
  - {{kind: simulated, name: nav, actions: {{move: [tiago]}}}}
clock: {{kind: virtual}}
"""

BINARY = b"\x00\x89PNG\r\n\x1a\n" + bytes(range(256))


def error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one ``error:`` line on stderr (and no traceback)."""
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.startswith("error: ")]
    assert len(lines) == 1, err
    return lines[0]


@pytest.fixture()
def files(tmp_path: Path) -> dict[str, str]:
    (tmp_path / "problem.pddl").write_text(PROBLEM)
    (tmp_path / "mission.yaml").write_text(MISSION)
    (tmp_path / "binary.bin").write_bytes(BINARY)
    (tmp_path / "late.pddl").write_bytes(b"(define (domain x)\n  (:requirements \xff))\n")
    (tmp_path / "folder").mkdir()
    return {
        name.split(".")[0]: str(tmp_path / name)
        for name in ("problem.pddl", "mission.yaml", "binary.bin", "late.pddl", "folder")
    }


# ------------------------------------------------------------------ unreadable files


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["validate", "{binary}"], "binary.bin:1:2: cannot read domain file: not UTF-8"),
        (["validate", "{late}"], "late.pddl:2:18: cannot read domain file: not UTF-8"),
        (["validate", DOMAIN, "--problem", "{binary}"], "binary.bin:1:2: cannot read problem"),
        (
            ["validate", DOMAIN, "--problem", "{problem}", "--plan", "{binary}"],
            "binary.bin:1:2: cannot read plan file",
        ),
        (["plan", DOMAIN, "{binary}"], "binary.bin:1:2: cannot read problem file"),
        (["plan", "{binary}", "{problem}"], "binary.bin:1:2: cannot read domain file"),
        (["run", "{binary}"], "binary.bin:1:2: cannot read mission file"),
        (["run", "{mission}", "--plan", "{binary}"], "binary.bin:1:2: cannot read plan"),
        (["run", "{mission}", "--plan", "{folder}"], "folder: cannot read plan file: Is a"),
        (["run", "{mission}", "--plan", "missing.plan"], "missing.plan: cannot read plan"),
        (["terminal", DOMAIN, "--problem", "{binary}"], "binary.bin:1:2: cannot read problem"),
        (["terminal", DOMAIN, "--source", "{binary}"], "binary.bin:1:2: cannot read command"),
        (["terminal", DOMAIN, "--source", "{folder}"], "folder: cannot read command file: Is a"),
        (["terminal", DOMAIN, "--source", "missing.txt"], "missing.txt: cannot read command file"),
    ],
)
def test_unreadable_file_is_one_line_naming_it(
    argv: list[str],
    expected: str,
    files: dict[str, str],
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr("sys.stdin", open("/dev/null"))  # noqa: SIM115 (closed by pytest)
    assert main([a.format(**files) for a in argv]) == 2
    assert expected in error_line(capsys)


def test_files_saved_with_a_byte_order_mark_are_read(
    files: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain = tmp_path / "domain.pddl"
    domain.write_bytes(b"\xef\xbb\xbf" + Path(DOMAIN).read_bytes())
    problem = tmp_path / "problem.pddl"
    problem.write_bytes(b"\xef\xbb\xbf" + PROBLEM.encode())
    assert main(["validate", str(domain), "--problem", str(problem)]) == 0
    assert "problem p: 3 objects" in capsys.readouterr().out


def test_terminal_source_command_names_a_binary_file(
    files: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from plansys_bridge.knowledge.domain_expert import DomainExpert
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.terminal import Terminal

    domain = DomainExpert.from_files([DOMAIN])
    terminal = Terminal(domain, ProblemExpert(domain))
    result = terminal.execute_line(f"source {files['binary']}")
    assert result.startswith("error: ")
    assert "binary.bin:1:2: cannot read command file: not UTF-8" in result


# ------------------------------------------------------------------ numeric options


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["run", "{mission}", "--clock", "wall", "--time-scale", "0"], "--time-scale: must be"),
        (["run", "{mission}", "--clock", "wall", "--time-scale", "-1"], "--time-scale: must be"),
        (["run", "{mission}", "--clock", "wall", "--time-scale", "nan"], "--time-scale: must be"),
        (["run", "{mission}", "--clock", "wall", "--time-scale", "inf"], "--time-scale: must be"),
        (["run", "{mission}", "--time-scale", "0.5"], "--time-scale: applies to the wall clock"),
        (["demo", "--clock", "virtual", "--time-scale", "0"], "--time-scale: must be"),
        (["performers", "{mission}", "--time-scale", "-1"], "--time-scale: must be"),
        (["performers", "{mission}", "--duration", "0"], "--duration: must be"),
        (["plan", DOMAIN, "{problem}", "--timeout", "nan"], "timeout must be positive and finite"),
        (["plan", DOMAIN, "{problem}", "--timeout", "inf"], "timeout must be positive and finite"),
        (["plan", DOMAIN, "{problem}", "--threads", "-2"], "--threads: must be >= 1, got -2"),
        (["plan", DOMAIN, "{problem}", "--improve", "-1"], "--improve: must be a finite number"),
        (["terminal", DOMAIN, "--timeout", "nan"], "--timeout: must be a finite number > 0"),
        (["experiment", "cooking", "--hours", "inf"], "--hours: must be a finite number > 0"),
        (["experiment", "cooking", "--plans", "0"], "--plans: must be >= 1, got 0"),
        (["experiment", "cooking", "--battery-drops", "nan"], "--battery-drops: must be"),
        (["experiment", "cooking", "--clock", "wall", "--time-scale", "inf"], "--time-scale"),
    ],
)
def test_nonsense_number_is_refused_naming_the_option(
    argv: list[str], expected: str, files: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([a.format(**files) for a in argv]) == 2
    assert expected in error_line(capsys)


# ------------------------------------------------------------------ mission files


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        (
            "kind: simulated",
            "kind: simulatd",
            "mission.yaml:9:6: performers[0].kind: unknown performer kind 'simulatd'",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {move: [tiago]}, duratons: {move: 2}",
            "mission.yaml:9:60: performers[0].duratons: unknown key",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {mvoe: [tiago]}",
            "mission.yaml:9:44: performers[0].actions.mvoe: "
            "domain flat_navigation has no action 'mvoe'",
        ),
        (
            "clock: {kind: virtual}",
            "clock: {kind: virtual}\nevents: [{at: 2, add_predicate: (connected hall mars)}]",
            "mission.yaml:11:18: events[0].add_predicate: <atom>:1:17: unknown object 'mars'",
        ),
        (
            "clock: {kind: virtual}",
            "clock: {kind: virtual}\nevents: [{at: 2, set_function: (= (travel_tim hall) 3)}]",
            "mission.yaml:11:18: events[0].set_function: "
            "<fluent>:1:5: unknown function 'travel_tim'",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {move: [tiagoo]}",
            "mission.yaml:9:51: performers[0].actions.move[0]: no object 'tiagoo' in the mission's",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {move: [tiago]}, durations: {mvoe: 3}",
            "mission.yaml:9:72: performers[0].durations.mvoe: not one of this performer's actions",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {move: [tiago]}, durations: {'(fly tiago a b)': 3}",
            "mission.yaml:9:72: performers[0].durations.(fly tiago a b): "
            "not one of this performer's",
        ),
        (
            f"domain: {DOMAIN}",
            "domain: []",
            "mission.yaml:2:1: domain: List should have at least 1 item",
        ),
        (
            "clock: {kind: virtual}",
            "clock: {kind: virtual}\nname: again",
            "mission.yaml:11:1: not valid YAML: duplicate key 'name'",
        ),
        (
            "actions: {move: [tiago]}",
            "actions: {move: [tiago], move: []}",
            "mission.yaml:9:59: not valid YAML: duplicate key 'move'",
        ),
    ],
)
def test_mission_mistake_names_file_and_key(
    old: str,
    new: str,
    expected: str,
    files: dict[str, str],
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = Path(files["mission"])
    path.write_text(MISSION.replace(old, new))
    assert main(["run", str(path)]) == 2
    assert expected in error_line(capsys)


def test_mission_events_are_checked_without_changing_the_knowledge(tmp_path: Path) -> None:
    from plansys_bridge.mission import build_knowledge
    from plansys_bridge.mission_config import load_mission
    from plansys_bridge.pddl.parser import parse_domain_files

    path = tmp_path / "mission.yaml"
    path.write_text(
        MISSION
        + "events:\n"
        + "  - {at: 1, add_predicate: (connected hall kitchen)}\n"
        + "  - {at: 2, remove_predicate: (robot_at tiago kitchen)}\n"
        + "  - {at: 3, set_function: (= (travel_time hall kitchen) 7)}\n"
    )
    mission = load_mission(path)
    knowledge = build_knowledge(mission, parse_domain_files(mission.domain_paths))
    facts = {str(a) for a in knowledge.get_predicates()}
    assert facts == {"(robot_at tiago kitchen)", "(connected kitchen hall)"}
    assert knowledge.get_function("(travel_time hall kitchen)") is None


def test_mission_yaml_merge_keys_still_work(tmp_path: Path) -> None:
    from plansys_bridge.mission_config import load_mission

    path = tmp_path / "mission.yaml"
    path.write_text(
        MISSION.replace(
            "performers:\n  - {kind: simulated, name: nav, actions: {move: [tiago]}}",
            "performers:\n  - &nav {kind: simulated, name: nav, actions: {move: [tiago]}}\n"
            "  - {<<: *nav, name: nav2}",
        )
    )
    assert [p.name for p in load_mission(path).performers] == ["nav", "nav2"]


# ------------------------------------------------------------------ Ctrl-C, SIGTERM


@pytest.mark.parametrize(
    ("signal_name", "code", "line"),
    [("SIGINT", 130, "interrupted"), ("SIGTERM", 143, "terminated")],
)
def test_ctrl_c_or_sigterm_during_a_wall_clock_run_stops_cleanly(
    signal_name: str, code: int, line: str, files: dict[str, str]
) -> None:
    """SIGINT (or SIGTERM) mid-action: the action is cancelled, one short line."""
    import signal
    import subprocess
    import sys

    path = Path(files["mission"])
    path.write_text(
        MISSION.replace("clock: {kind: virtual}", "clock: {kind: wall}").replace(
            "actions: {move: [tiago]}", "actions: {move: [tiago]}, durations: {move: 60}"
        )
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "plansys_bridge", "run", str(path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a child of a non-interactive shell may inherit SIGINT ignored
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert proc.stdout is not None
    for progress in proc.stdout:
        if "EXECUTING" in progress:
            break
    proc.send_signal(getattr(signal, signal_name))
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == code, err
    assert err.strip() == line
    assert "CANCELLED (move tiago kitchen hall)" in out


def test_terminal_quotes_at_most_40_characters_of_an_unknown_command() -> None:
    from plansys_bridge.knowledge.domain_expert import DomainExpert
    from plansys_bridge.knowledge.problem_expert import ProblemExpert
    from plansys_bridge.terminal import Terminal

    domain = DomainExpert.from_files([DOMAIN])
    result = Terminal(domain, ProblemExpert(domain)).execute_line("z" * 5000)
    assert result == f"error: unknown command '{'z' * 40}...' (try: help)"


# ------------------------------------------------------------------ | head


def _read_one_line_then_close(argv: list[str], stdin: str = "") -> tuple[int, str]:
    """Run the command with its stdout read by a reader that leaves after one line."""
    import subprocess
    import sys

    proc = subprocess.Popen(
        [sys.executable, "-m", "plansys_bridge", *argv],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdin is not None and proc.stdout is not None and proc.stderr is not None
    proc.stdin.write(stdin)
    proc.stdin.close()
    assert proc.stdout.readline()
    proc.stdout.close()
    err = proc.stderr.read()
    return proc.wait(timeout=60), err


def test_mission_output_to_a_closed_pipe_finishes_the_mission_quietly(
    files: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import os
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader has gone before the first line
    with os.fdopen(write_end, "w") as stream:
        monkeypatch.setattr(sys, "stdout", stream)
        assert main(["run", files["mission"]]) == 0  # the mission ran to its end
        sys.stdout.flush()  # what is left goes nowhere, without an error


def test_terminal_output_piped_to_head_ends_quietly() -> None:
    code, err = _read_one_line_then_close(["terminal", DOMAIN], "get domain\n" * 2000)
    assert (code, err) == (141, "")
