"""Reading the text files a user names: PDDL, plans, mission files, command files.

Every command reads files the same way so that every unreadable one fails the same
way: one line naming the path and the reason (``missing.pddl: cannot read domain
file: No such file or directory``), and for a binary or wrongly encoded file the
line and column of the first byte that is not UTF-8, never a decoding traceback.
A byte order mark, which some Windows editors write, is not part of the text.
"""

from __future__ import annotations

from pathlib import Path

from plansys_bridge.errors import PlansysBridgeError, SourceLocation

__all__ = ["TextFileError", "read_text"]


class TextFileError(PlansysBridgeError):
    """A file cannot be read as UTF-8 text (missing, a directory, unreadable, binary).

    ``location`` is the first undecodable byte (1-based line and column) when the
    file was read but is not text; ``reason`` is the message without the place.
    """

    def __init__(self, path: str, reason: str, location: SourceLocation | None = None) -> None:
        self.path = path
        self.reason = reason
        self.location = location
        super().__init__(f"{location or path}: {reason}")


def read_text(path: str | Path, what: str = "file") -> str:
    """The UTF-8 text of ``path``; TextFileError naming the path when it cannot be read."""
    name = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise TextFileError(name, f"cannot read {what}: {exc.strerror or exc}") from exc
    except ValueError as exc:  # "embedded null byte": no file system allows one in a name
        raise TextFileError(repr(name), f"cannot read {what}: a NUL byte in its name") from exc
    try:
        return data.decode("utf-8-sig")  # the codec drops a byte order mark, if any
    except UnicodeDecodeError as exc:
        data = exc.object  # the bytes after the mark: offsets below count from there
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        line = data.count(b"\n", 0, exc.start) + 1
        column = len(data[line_start : exc.start].decode("utf-8", "replace")) + 1
        raise TextFileError(
            name,
            f"cannot read {what}: not UTF-8 text (byte 0x{data[exc.start]:02x}); "
            "is it a binary file?",
            SourceLocation(name, line, column),
        ) from exc
