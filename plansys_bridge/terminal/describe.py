"""How the terminal prints domain and knowledge items (PlanSys2's listing shapes).

A count line then one item per line, tab-indented (``Types: 2`` / ``\\trobot``), as
``plansys2_terminal`` prints them, so scripts written against it still read ours.
"""

from __future__ import annotations

from plansys_bridge.pddl.model import Action, AnyAction, DerivedPredicate, TypedName

__all__ = ["describe_action", "describe_derived", "listing", "params", "signature"]


def listing(title: str, items: list[str], indent: str = "\t") -> str:
    return "\n".join([f"{title}: {len(items)}", *(indent + i for i in items)])


def params(parameters: tuple[TypedName, ...]) -> list[str]:
    return [f"{p.name} - {_types(p.types)}" for p in parameters]


def _types(types: tuple[str, ...]) -> str:
    return types[0] if len(types) == 1 else "(either " + " ".join(types) + ")"


def signature(name: str, parameters: tuple[TypedName, ...]) -> str:
    return "(" + " ".join([name, *params(parameters)]) + ")"


def describe_action(action: AnyAction) -> str:
    from plansys_bridge.pddl.writer import write_condition, write_effect, write_num_expr

    lines = [
        f"Type: {'action' if isinstance(action, Action) else 'durative-action'}",
        f"Name: {action.name}",
        listing("Parameters", params(action.parameters)),
    ]
    if isinstance(action, Action):
        lines.append(f"Precondition: {write_condition(action.precondition)}")
        lines.append(f"Effect: {write_effect(action.effect)}")
    else:
        for constraint in action.duration:
            lines.append(
                f"Duration: ({constraint.op} ?duration {write_num_expr(constraint.value)})"
            )
        lines.append(f"At start requirements: {write_condition(action.at_start)}")
        lines.append(f"Over all requirements: {write_condition(action.over_all)}")
        lines.append(f"At end requirements: {write_condition(action.at_end)}")
        lines.append(f"At start effect: {write_effect(action.start_effect)}")
        lines.append(f"At end effect: {write_effect(action.end_effect)}")
    return "\n".join(lines)


def describe_derived(rules: list[DerivedPredicate]) -> str:
    """Each rule of one derived predicate: its parameters and its condition."""
    from plansys_bridge.pddl.writer import write_condition

    blocks = []
    for rule in rules:
        blocks.append(
            "\n".join(
                [
                    listing("Parameters", params(rule.head.parameters)),
                    f"Preconditions: {write_condition(rule.condition)}",
                ]
            )
        )
    return "\n".join(blocks)
