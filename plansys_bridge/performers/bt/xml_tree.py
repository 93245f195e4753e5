"""Read BehaviorTree.CPP v4 XML into a small element tree that keeps positions.

PlanSys2's BT actions describe their trees in BehaviorTree.CPP's XML
(``<root BTCPP_format="4" main_tree_to_execute="MainTree">`` holding
``<BehaviorTree ID="...">`` elements). Elements are read with expat so each keeps
its line and column, and every error names ``file:line:col``.
"""

from __future__ import annotations

import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path

from plansys_bridge.errors import ConfigError

__all__ = ["BtXmlError", "Element", "main_tree", "parse_bt_xml"]


class BtXmlError(ConfigError):
    """A behaviour tree file that cannot be read or built, at ``file:line:col``."""


@dataclass
class Element:
    tag: str
    attrs: dict[str, str]
    file: str
    line: int
    column: int
    children: list[Element] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    def error(self, message: str) -> BtXmlError:
        return BtXmlError(f"{self.where}: <{self.tag}>: {message}")


def parse_bt_xml(text: str, file: str = "<bt>") -> Element:
    """The root element of ``text``; a malformed file raises :class:`BtXmlError`."""
    parser = xml.parsers.expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        element = Element(
            tag, dict(attrs), file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1
        )
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def end(_tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as exc:
        raise BtXmlError(
            f"{file}:{exc.lineno}:{exc.offset + 1}: not well-formed XML "
            f"({xml.parsers.expat.ErrorString(exc.code)})"
        ) from exc
    return roots[0]


def read_bt_file(path: Path) -> Element:
    from plansys_bridge.textfile import TextFileError, read_text

    try:
        text = read_text(path, "behaviour tree file")
    except TextFileError as exc:
        raise BtXmlError(str(exc)) from exc
    return parse_bt_xml(text, str(path))


def main_tree(root: Element) -> Element:
    """The tree to run: ``main_tree_to_execute`` (v4 also: ``main_tree_to_execute``
    missing and a single ``BehaviorTree``); returns its one child node."""
    if root.tag != "root":
        if root.tag == "BehaviorTree":
            trees = [root]
        else:
            raise root.error('expected <root BTCPP_format="4"> or <BehaviorTree>')
    else:
        version = root.attrs.get("BTCPP_format", "4")
        if version != "4":
            raise root.error(f"BTCPP_format {version!r}: only format 4 is read")
        trees = [c for c in root.children if c.tag == "BehaviorTree"]
        if not trees:
            raise root.error("no <BehaviorTree> in the file")
    wanted = root.attrs.get("main_tree_to_execute") if root.tag == "root" else None
    if wanted is not None:
        found = [t for t in trees if t.attrs.get("ID") == wanted]
        if not found:
            ids = ", ".join(t.attrs.get("ID", "?") for t in trees)
            raise root.error(f"main_tree_to_execute {wanted!r} is not a BehaviorTree ID ({ids})")
        tree = found[0]
    elif len(trees) == 1:
        tree = trees[0]
    else:
        raise root.error("several BehaviorTrees and no main_tree_to_execute")
    if len(tree.children) != 1:
        raise tree.error(f"a BehaviorTree has exactly one root node, found {len(tree.children)}")
    return tree.children[0]
