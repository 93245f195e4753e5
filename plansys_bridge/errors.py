"""The project's exception tree.

Every error the project raises on purpose derives from :class:`PlansysBridgeError`,
so a caller can catch one type and still tell the cases apart. Errors carry the
place they refer to (a file:line:col, a topic, a link URL, a config key) because a
robotics engineer reading a log at the robot needs to know *where*, not just *what*.
Subpackages add precise subclasses; they always ``raise ... from`` the cause.
"""

from __future__ import annotations

from dataclasses import dataclass


class PlansysBridgeError(Exception):
    """Root of every error this project raises deliberately."""


@dataclass(frozen=True)
class SourceLocation:
    """A place in a source text: file name, 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


class PddlError(PlansysBridgeError):
    """A PDDL text could not be turned into a valid model.

    ``location`` names the offending place and ``snippet`` quotes the source line
    with a caret under the column, so the message reads like a compiler's.
    """

    def __init__(
        self,
        message: str,
        location: SourceLocation | None = None,
        snippet: str | None = None,
    ) -> None:
        self.message = message
        self.location = location
        self.snippet = snippet
        text = f"{location}: {message}" if location is not None else message
        if snippet:
            text = f"{text}\n{snippet}"
        super().__init__(text)


class PddlSyntaxError(PddlError):
    """The text is not PDDL: unbalanced parentheses, unknown keyword, bad token."""


class PddlSemanticError(PddlError):
    """The text parses but is wrong: unknown type/predicate/object, arity, types."""


class KnowledgeError(PlansysBridgeError):
    """A change to the knowledge base was refused; the knowledge is unchanged."""


class PlanningError(PlansysBridgeError):
    """A solver failed, timed out, or was given input it cannot handle."""


class PlanValidationError(PlansysBridgeError):
    """A plan does not achieve its goal or breaks a condition on the way."""


class ExecutionError(PlansysBridgeError):
    """The executor could not run a plan (bad plan graph, hub failure, ...)."""


class HubError(PlansysBridgeError):
    """A message could not be published, delivered or decoded on the hub."""


class ConfigError(PlansysBridgeError):
    """A configuration file is missing a key, has a typo, or a wrong value.

    ``key`` is the dotted path of the offending entry (``performers[2].url``);
    ``line`` and ``column`` (1-based) where it is in ``file``, when known, make the
    message read like a compiler's: ``mission.yaml:12:7: performers[2].url: ...``.
    """

    def __init__(
        self,
        message: str,
        key: str | None = None,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        self.key = key
        self.file = file
        self.line = line
        self.column = column
        self.reason = message
        """The message without the place."""
        if file and line:
            where = f"{file}:{line}:{column or 1}: {key}" if key else f"{file}:{line}:{column or 1}"
        else:
            where = ":".join(p for p in (file, key) if p)
        super().__init__(f"{where}: {message}" if where else message)


class AdapterError(PlansysBridgeError):
    """A hardware adapter failed: link lost, command refused, bad frame."""


class PluginError(PlansysBridgeError):
    """A plugin (performer kind, solver) is unknown or its dependency is missing."""
