"""Temporal plans and PlanSys2's plan text format.

A plan file line reads ``0.000: (move r2d2 kitchen bedroom)  [5.000]`` (POPF, OPTIC
and PlanSys2's ``run plan-file``). Solvers differ in details (LPG-td upper-cases and
adds a stray ``)``; IPC output may omit the duration for instantaneous actions), so
the reader is lenient in form but strict in content: a line that is not a plan step
raises :class:`PlanFormatError` naming file and line.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

from plansys_bridge.errors import PlanningError, SourceLocation
from plansys_bridge.hub.messages import Plan as PlanMsg
from plansys_bridge.hub.messages import PlanItem


class PlanFormatError(PlanningError):
    """A plan text line could not be read."""

    def __init__(self, message: str, location: SourceLocation | None = None) -> None:
        self.location = location
        super().__init__(f"{location}: {message}" if location else message)


@dataclass(frozen=True, init=False)
class PlanStep:
    """One grounded action in a plan: start time, name, arguments, duration.

    Its :attr:`text` is written once, when the step is made: the executor, the DOT
    view and every log line name an action by it, several times per action, and
    joining the strings again each time was a measurable part of running a plan.
    """

    time: float
    action: str
    arguments: tuple[str, ...] = ()
    duration: float = 0.0
    text: str = field(init=False, repr=False, compare=False)
    """``(move r2d2 a b)``, the action as PlanSys2 writes it."""

    def __init__(
        self, time: float, action: str, arguments: tuple[str, ...] = (), duration: float = 0.0
    ) -> None:
        # Written straight into the instance dict, as a frozen dataclass's own
        # __init__ would through object.__setattr__ (once per field).
        d = self.__dict__
        d["time"] = time
        d["action"] = action
        d["arguments"] = arguments
        d["duration"] = duration
        d["text"] = "(" + " ".join((action, *arguments)) + ")"

    @property
    def end(self) -> float:
        return self.time + self.duration

    def to_item(self) -> PlanItem:
        return PlanItem(time=self.time, action=self.text, duration=self.duration)

    @classmethod
    def from_item(cls, item: PlanItem) -> PlanStep:
        name, args = parse_action_text(item.action)
        return cls(item.time, name, args, item.duration)


@dataclass(frozen=True)
class Plan:
    steps: tuple[PlanStep, ...] = ()

    def __iter__(self) -> Iterator[PlanStep]:
        return iter(self.steps)

    def __len__(self) -> int:
        return len(self.steps)

    @property
    def makespan(self) -> float:
        return max((s.end for s in self.steps), default=0.0)

    def sorted(self) -> Plan:
        return Plan(tuple(sorted(self.steps, key=lambda s: (s.time, s.text))))

    def to_msg(self) -> PlanMsg:
        """The plan as the hub sends it (each item as :meth:`PlanStep.to_item` makes
        it, made here in one comprehension: the executor sends every plan it runs)."""
        return PlanMsg(
            tuple([PlanItem(time=s.time, action=s.text, duration=s.duration) for s in self.steps])
        )

    @classmethod
    def from_msg(cls, msg: PlanMsg) -> Plan:
        return cls(tuple(PlanStep.from_item(i) for i in msg.items))

    def to_text(self, precision: int = 3) -> str:
        return format_plan(self, precision)


_ACTION_RE = re.compile(r"^\(\s*([^\s()]+)((?:\s+[^\s()]+)*)\s*\)$")
_LINE_RE = re.compile(
    r"^\s*(?P<time>[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s*:\s*"
    r"(?P<action>\([^()]*\))\s*\)?\s*"
    r"(?:\[\s*(?P<dur>[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s*\])?\s*\)?\s*(?:;.*)?$"
)


def parse_action_text(text: str) -> tuple[str, tuple[str, ...]]:
    """``"(move r2d2 a b)"`` -> ``("move", ("r2d2", "a", "b"))``, lower-cased."""
    m = _ACTION_RE.match(text.strip())
    if m is None:
        raise PlanFormatError(f"not an action: {text!r}")
    return m.group(1).lower(), tuple(a.lower() for a in m.group(2).split())


def parse_plan(text: str, filename: str = "<plan>") -> Plan:
    """Read PlanSys2/POPF/OPTIC/LPG/IPC plan text; comments and blank lines skipped."""
    steps: list[PlanStep] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith(";"):
            continue
        m = _LINE_RE.match(line)
        if m is None:
            raise PlanFormatError(
                f"expected 'TIME: (action args...) [DURATION]', got {line!r}",
                SourceLocation(filename, lineno, 1),
            )
        column = len(raw) - len(raw.lstrip()) + 1  # of the stripped line's start
        try:
            name, args = parse_action_text(m.group("action"))
        except PlanFormatError as exc:
            where = SourceLocation(filename, lineno, column + m.start("action"))
            raise PlanFormatError(str(exc), where) from exc
        for group in ("time", "dur"):
            if m.group(group) is not None and not math.isfinite(float(m.group(group))):
                where = SourceLocation(filename, lineno, column + m.start(group))
                raise PlanFormatError(f"number {m.group(group)} is out of range", where)
        dur = float(m.group("dur")) if m.group("dur") is not None else 0.0
        steps.append(PlanStep(float(m.group("time")), name, args, dur))
    return Plan(tuple(steps))


def format_plan(plan: Plan | Iterable[PlanStep], precision: int = 3) -> str:
    """Write PlanSys2's format, one step a line, three decimals (``precision`` more for
    solvers that separate happenings by less than a millisecond, such as LPG-td)."""
    steps = plan.steps if isinstance(plan, Plan) else tuple(plan)
    p = precision
    return "".join(f"{s.time:.{p}f}: {s.text}  [{s.duration:.{p}f}]\n" for s in steps)
