"""What every command shares: --version, -v/-q with timestamped log lines."""

from __future__ import annotations

import logging
import re

import pytest

from plansys_bridge import __version__
from plansys_bridge.cli import build_parser, main
from plansys_bridge.cli.verbosity import configure_logging


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"plansys-bridge {__version__}"


def test_every_command_takes_verbose_and_quiet() -> None:
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    assert commands is not None and len(commands) >= 7
    for name, sub in commands.items():
        options = {o for action in sub._actions for o in action.option_strings}
        assert {"-v", "--verbose", "-q", "--quiet"} <= options, name
    args = parser.parse_args(["validate", "d.pddl", "-vv"])
    assert args.verbose == 2 and not args.quiet
    with pytest.raises(SystemExit):  # both at once makes no sense
        parser.parse_args(["validate", "d.pddl", "-v", "-q"])


@pytest.mark.parametrize(
    ("argv", "level"),
    [
        (["-q"], logging.ERROR),
        ([], logging.WARNING),
        (["-v"], logging.INFO),
        (["-vv"], logging.DEBUG),
    ],
)
def test_log_levels_and_timestamps(
    argv: list[str], level: int, capsys: pytest.CaptureFixture[str]
) -> None:
    args = build_parser().parse_args(["validate", "d.pddl", *argv])
    root = logging.getLogger()
    saved = (root.level, list(root.handlers))
    try:
        configure_logging(args)
        assert root.level == level
        logging.getLogger("plansys_bridge.test").error("the drone is %s", "lost")
        line = capsys.readouterr().err.strip()
        stamp = r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3}"
        assert re.fullmatch(stamp + r" ERROR   plansys_bridge\.test: the drone is lost", line), line
    finally:
        root.handlers[:] = saved[1]
        root.setLevel(saved[0])


@pytest.mark.parametrize(("flag", "level"), [("-vv", logging.DEBUG), ("-q", logging.ERROR)])
def test_verbosity_may_come_before_the_command(
    flag: str, level: int, capsys: pytest.CaptureFixture[str]
) -> None:
    root = logging.getLogger()
    saved = (root.level, list(root.handlers))
    try:
        assert main([flag, "plan", "missing-domain.pddl"]) == 2  # an error, but logging is set
        assert root.level == level
        assert "error: " in capsys.readouterr().err
    finally:
        root.handlers[:] = saved[1]
        root.setLevel(saved[0])
    with pytest.raises(SystemExit):
        main(["-v", "plan", "-q", "d.pddl"])
