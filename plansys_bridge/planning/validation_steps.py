"""A plan's steps as happenings on its timeline, for the plan validator.

Each step is bound to its action (the arguments known objects of the parameters'
types) and, for a plain action, its start, end and over-all parts are grounded once
(:mod:`~plansys_bridge.planning.ground_parts`). Binding checked each argument's type
through the type hierarchy and grounding substituted every formula per step; here
each object and type is checked once per validation, and what grounds an action's
parts is compiled once per action.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from plansys_bridge.errors import PlansysBridgeError
from plansys_bridge.knowledge.evaluation import Evaluator
from plansys_bridge.knowledge.state import State
from plansys_bridge.pddl.model import NO_EFFECT, AnyAction, DurativeAction
from plansys_bridge.planning.happenings import BoundStep, Happening
from plansys_bridge.planning.mutex import CompiledParts, Footprints, GroundParts
from plansys_bridge.planning.plan import PlanStep

__all__ = ["StepProblem", "Timeline"]

Types = tuple[str, ...]

_ActionParts = tuple[CompiledParts | None, CompiledParts | None, CompiledParts | None]
"""(start, end or instant, over all) of one action, for :meth:`CompiledParts.ground`."""


class StepProblem(Exception):
    """A step that cannot be put on the timeline; the validator reports it."""

    def __init__(self, index: int, message: str) -> None:
        super().__init__(message)
        self.index = index
        self.message = message


class Timeline:
    """Binds and grounds a plan's steps in one state (see module docs)."""

    def __init__(self, ev: Evaluator, footprints: Footprints, state: State) -> None:
        self._ev = ev
        self._footprints = footprints
        self._state = state
        self._objects = dict(state.objects)
        self._compiled: dict[int, _ActionParts] = {}
        self._typed: dict[tuple[str, Types], bool] = {}
        self._signatures: dict[str, tuple[AnyAction, tuple[str, ...], tuple[Types, ...]]] = {}
        self.over_all: dict[int, GroundParts | None] = {}
        """Each durative step's over-all condition with its arguments in place."""

    def happenings(self, steps: Sequence[PlanStep]) -> list[Happening]:
        """Every step's happenings in time order (ends before starts at one time)."""
        out: list[Happening] = []
        for i, step in enumerate(steps):
            if not math.isfinite(step.time) or step.time < 0:
                raise StepProblem(i, f"start time {step.time} is not a time >= 0")
            action, bindings = self._bind(i, step)
            g = BoundStep(action, bindings)
            compiled = self._compiled.get(id(action))
            if compiled is None:
                compiled = self._compiled[id(action)] = self._compile(action, tuple(bindings))
            values = tuple(bindings.values())
            at_start, at_end, during = compiled
            end = None if at_end is None else at_end.ground(values, bindings)
            if isinstance(action, DurativeAction):
                if not math.isfinite(step.duration) or step.duration < 0:
                    raise StepProblem(i, f"duration {step.duration} is not a duration >= 0")
                self.over_all[i] = None if during is None else during.ground(values, bindings)
                start = None if at_start is None else at_start.ground(values, bindings)
                out.append(Happening(step.time, i, "start", g, step.duration, start))
                out.append(Happening(step.time + step.duration, i, "end", g, step.duration, end))
            else:
                out.append(Happening(step.time, i, "instant", g, None, end))
        out.sort(key=Happening.sort_key)
        return out

    def _compile(self, action: AnyAction, names: tuple[str, ...]) -> _ActionParts:
        """What grounds an action's start, end (or instant) and over-all parts."""
        compiled = self._footprints.compiled
        if isinstance(action, DurativeAction):
            return (
                compiled(action.at_start, action.start_effect, names),
                compiled(action.at_end, action.end_effect, names),
                compiled(action.over_all, NO_EFFECT, names),
            )
        return (None, compiled(action.precondition, action.effect, names), None)

    def _bind(self, index: int, step: PlanStep) -> tuple[AnyAction, dict[str, str]]:
        """The step's action and bindings, as :meth:`Evaluator.bind` with the state
        gives them; each object and parameter type is checked once per validation."""
        signature = self._signatures.get(step.action)
        if signature is None:
            try:
                action = self._ev.get_action(step.action)
            except PlansysBridgeError as exc:
                raise StepProblem(index, str(exc)) from exc
            params = action.parameters
            signature = (action, tuple(p.name for p in params), tuple(p.types for p in params))
            self._signatures[step.action] = signature
        action, names, types = signature
        args = tuple([a.lower() for a in step.arguments])
        typed = self._typed
        ok = len(args) == len(names)
        for arg, wanted in zip(args, types, strict=False):
            known = typed.get((arg, wanted))
            if known is None:
                kind = self._objects.get(arg)
                known = typed[(arg, wanted)] = kind is not None and (
                    self._ev.types.is_subtype_of_any((kind,), wanted)
                )
            ok = ok and known
        if not ok:
            try:  # the evaluator's own words for what is wrong
                self._ev.bind(step.action, step.arguments, self._state)
            except PlansysBridgeError as exc:
                raise StepProblem(index, str(exc)) from exc
        return action, dict(zip(names, args, strict=True))
