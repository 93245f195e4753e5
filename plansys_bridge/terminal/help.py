"""The terminal's help: all commands (``help``, ``?``) or one (``help run``)."""

from __future__ import annotations

__all__ = ["COMMAND_HELP", "HELP", "help_text"]

COMMAND_HELP: dict[str, str] = {
    "get": """\
  get model types | predicates | functions | actions | deriveds
  get model predicate NAME | function NAME | action NAME | derived NAME
  get problem instances | predicates | functions | goal
  get problem                   the knowledge as a PDDL problem
  get domain                    the (merged) domain as PDDL
  get plan                      plan from the current knowledge to the goal""",
    "set": """\
  set instance NAME TYPE
  set predicate (p a b)
  set function (= (f a b) 3)
  set goal (and (p a b) ...)""",
    "remove": """\
  remove instance NAME | predicate (p a b) | function (f a b) | goal""",
    "run": """\
  run                           plan and execute to the goal (replanning on failure)
  run num_actions N             plan, then execute only the plan's first N actions
  run action (a x y)            execute that one action, then stop (also: run (a x y))
  run plan-file FILE            execute exactly the plan in FILE, then stop""",
    "check": """\
  check actors                  the performers alive now: state, actions, last heartbeat""",
    "source": """\
  source FILE [0|1]             run the commands in FILE (1: echo each command first)""",
    "help": """\
  help | ? [COMMAND]            all commands, or one of them""",
    "quit": """\
  quit                          leave (also: exit, Ctrl-D)""",
}
COMMAND_HELP["?"] = COMMAND_HELP["help"]

HELP = "Commands:\n" + "\n".join(text for name, text in COMMAND_HELP.items() if name != "?")


def help_text(command: str | None) -> str | None:
    """The help for ``command`` (all of it for None); None for an unknown command."""
    if command is None:
        return HELP
    return COMMAND_HELP.get(command.lower())
