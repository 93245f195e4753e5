"""Tab completion for the terminal: commands, then the domain's and the knowledge's names.

PlanSys2's terminal completes its command words with readline; here the words that
follow complete too: instance names inside ``(...)``, predicate names after
``set predicate (``, action names after ``run (``, types after ``set instance X``.
:func:`candidates` is a pure function of the line so that it can be tested without a
terminal; :func:`install` hooks it into readline.
"""

from __future__ import annotations

from collections.abc import Callable

from plansys_bridge.knowledge.problem_expert import ProblemExpert

__all__ = ["DELIMITERS", "candidates", "install"]

DELIMITERS = " \t\n()"
"""readline splits words at these, so ``(robot_at le`` completes ``le``."""

_WORDS: dict[tuple[str, ...], list[str]] = {
    (): ["get", "set", "remove", "run", "check", "source", "help", "?", "quit"],
    ("get",): ["model", "problem", "domain", "plan"],
    ("set",): ["instance", "predicate", "function", "goal"],
    ("remove",): ["instance", "predicate", "function", "goal"],
    ("run",): ["action", "num_actions", "plan-file"],
    ("check",): ["actors"],
    ("get", "problem"): ["instances", "predicates", "functions", "goal"],
    ("get", "model"): [
        "types",
        "predicates",
        "functions",
        "actions",
        "deriveds",
        "predicate",
        "function",
        "action",
        "derived",
    ],
}
_WORDS[("help",)] = _WORDS[("?",)] = _WORDS[()]


def candidates(line: str, knowledge: ProblemExpert) -> list[str]:
    """Completions of the last (partial) word of ``line``, the text before the cursor."""
    ends_in_word = bool(line) and line[-1] not in DELIMITERS
    words = line.replace("(", " ( ").replace(")", " ) ").split()
    partial = words.pop() if ends_in_word and words else ""
    options = _options(words, knowledge)
    return sorted({o for o in options if o.startswith(partial.lower())})


def _options(words: list[str], knowledge: ProblemExpert) -> list[str]:
    de = knowledge.domain_expert
    lowered = [w.lower() for w in words]
    plain = tuple(w for w in lowered if w not in "()")
    if "(" in lowered:
        opened = len(lowered) - 1 - lowered[::-1].index("(")
        inside = lowered[opened + 1 :]
        if inside:  # after the predicate, function or action name: objects
            return list(knowledge.get_instances()) + list(de.get_constants())
        if plain[:1] == ("run",):
            return de.get_action_names()
        functions = [f.name for f in de.get_functions()]
        if plain[:2] in (("set", "function"), ("remove", "function")):
            return functions
        if plain[:2] == ("set", "goal"):
            return ["and", "or", "not", *(p.name for p in de.get_predicates())]
        return [p.name for p in de.get_predicates()]
    if plain in _WORDS:
        return _WORDS[plain]
    if len(plain) == 3 and plain[:2] == ("set", "instance"):
        return de.get_types()
    if plain == ("remove", "instance"):
        return list(knowledge.get_instances())
    if len(plain) == 3 and plain[:2] == ("get", "model"):
        kind = plain[2]
        if kind == "predicate":
            return [p.name for p in de.get_predicates()]
        if kind == "function":
            return [f.name for f in de.get_functions()]
        if kind == "action":
            return de.get_action_names()
        if kind == "derived":
            return sorted({r.head.name for r in de.get_derived()})
    if plain in (("help",), ("?",)):
        return _WORDS[()]
    return []


def install(knowledge: ProblemExpert) -> Callable[[str, int], str | None] | None:
    """Make readline complete terminal commands; returns the completer (None when
    readline is not available, e.g. on Windows without pyreadline)."""
    try:
        import readline
    except ImportError:
        return None
    matches: list[str] = []

    def complete(text: str, state: int) -> str | None:
        if state == 0:
            before = readline.get_line_buffer()[: readline.get_endidx()]
            matches[:] = candidates(before, knowledge)
        return matches[state] if state < len(matches) else None

    readline.set_completer_delims(DELIMITERS)
    readline.set_completer(complete)
    if "libedit" in (readline.__doc__ or ""):
        readline.parse_and_bind("bind ^I rl_complete")
    else:
        readline.parse_and_bind("tab: complete")
    return complete
