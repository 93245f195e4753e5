"""A table in insertion order that logs its changes, to undo them or report them.

Why: the problem expert must make every change all-or-nothing and tell subscribers
exactly what moved. Copying its tables before each change and comparing them after
costs time in the number of instances and facts; logging the few entries a change
touches costs time in the size of the change. Undo must also give back the original
insertion order (listings keep it), so each key keeps the sequence number it was
inserted with and a rollback that puts keys back sorts the table by it.
"""

from __future__ import annotations

from collections.abc import (
    Collection,
    ItemsView,
    Iterable,
    Iterator,
    KeysView,
    Mapping,
    ValuesView,
)
from typing import Generic, TypeVar

K = TypeVar("K")
V = TypeVar("V")


class _Missing:
    """Marks a key that was not in the table."""

    def __repr__(self) -> str:
        return "MISSING"


MISSING = _Missing()


class JournaledTable(Mapping[K, V], Generic[K, V]):
    """A read-only mapping to its users; ``set``/``delete`` write and log."""

    __slots__ = ("_data", "_log", "_next", "_seq", "writes")

    def __init__(self) -> None:
        self.writes = 0
        """Counts every write and undo: a cache of answers read from the table keeps
        the count it was filled at and is stale once the count moves."""
        self._data: dict[K, V] = {}
        self._seq: dict[K, int] = {}
        self._next = 0
        self._log: list[tuple[K, V | _Missing, int]] = []

    # ------------------------------------------------------------------ reading

    def __getitem__(self, key: K) -> V:
        return self._data[key]

    def __contains__(self, key: object) -> bool:
        return key in self._data

    def __iter__(self) -> Iterator[K]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def get(self, key: K, default: V | None = None) -> V | None:  # type: ignore[override]
        return self._data.get(key, default)

    # The dict's own views: Mapping's generic ones call __getitem__ once per key.
    def keys(self) -> KeysView[K]:
        return self._data.keys()

    def items(self) -> ItemsView[K, V]:
        return self._data.items()

    def values(self) -> ValuesView[V]:
        return self._data.values()

    def copy(self) -> dict[K, V]:
        """A plain dict of the entries, in insertion order."""
        return self._data.copy()

    # ------------------------------------------------------------------ writing

    def set(self, key: K, value: V) -> None:
        self.set_many((key,), value)

    def set_many(self, keys: Iterable[K], value: V) -> dict[K, None]:
        """``set(key, value)`` for each key in turn, in one call (a whole effect's
        facts); returns the keys that were not in the table, in order."""
        data, seq, log = self._data, self._seq, self._log
        new: dict[K, None] = {}
        for key in keys:
            size = len(data)
            old = data.setdefault(key, value)  # one lookup to read and, if new, write
            self.writes += 1
            if len(data) != size:  # it was not there (nor in _seq: both or neither)
                log.append((key, MISSING, -1))
                seq[key] = self._next
                self._next += 1
                new[key] = None
            else:
                log.append((key, old, seq[key]))
                if old is not value:
                    data[key] = value
        return new

    def delete(self, key: K) -> None:
        """Remove ``key`` (KeyError when absent)."""
        self.writes += 1
        self._log.append((key, self._data.pop(key), self._seq.pop(key)))

    def discard(self, key: K) -> None:
        self.discard_many((key,))

    def discard_many(self, keys: Iterable[K]) -> dict[K, None]:
        """``discard(key)`` for each key in turn, in one call; returns the keys that
        were in the table, in order."""
        data, seq, log = self._data, self._seq, self._log
        gone: dict[K, None] = {}
        for key in keys:
            old = data.pop(key, MISSING)
            if old is not MISSING:
                self.writes += 1
                log.append((key, old, seq.pop(key)))
                gone[key] = None
        return gone

    def swap(
        self, gone: Collection[K], came: Collection[K], value: V
    ) -> tuple[dict[K, None], dict[K, None]]:
        """``discard_many(gone)`` then ``set_many(came, value)`` as one step, all or
        nothing, that leaves the log as it was: for a change complete in itself,
        which nothing will undo or scan later. Returns (keys that went, keys that
        were not there).

        Why it logs nothing: the executor swaps an effect's facts twice per action,
        and the log entries ``discard_many`` and ``set_many`` write would be dropped
        at once. What a failure half way must put back is kept in local dicts
        instead (written with subscripts, no method call per key)."""
        data, seq = self._data, self._seq
        removed: dict[K, None] = {}
        new: dict[K, None] = {}
        lost: dict[K, tuple[V, int]] = {}  # removed keys: their value and place
        overwritten: dict[K, V] = {}  # keys there already that get ``value``
        nxt = self._next
        writes = 0
        try:
            for key in gone:
                if key in data:
                    lost[key] = (data[key], seq[key])
                    del data[key]
                    del seq[key]
                    removed[key] = None
                    writes += 1
            for key in came:
                writes += 1
                if key in data:
                    old = data[key]
                    if old is not value:
                        if key not in overwritten:
                            overwritten[key] = old
                        data[key] = value
                else:
                    data[key] = value
                    seq[key] = nxt
                    nxt += 1
                    new[key] = None
        except BaseException:
            self._put_back(new, overwritten, lost)
            raise
        self._next = nxt
        self.writes += writes
        return removed, new

    def exchange(
        self, gone: tuple[K, ...], came: tuple[K, ...], fresh: tuple[K, ...], value: V
    ) -> bool:
        """:meth:`swap` of keys without repeats in the case it is made for: every key
        of ``gone`` is there and no key of ``fresh`` (those of ``came`` not in
        ``gone``) is, so every key of ``gone`` goes and every key of ``came`` comes.
        False, nothing changed, in any other case. Counts the writes ``swap`` would
        for each key given once; as ``swap``, logs nothing.

        Why: an effect prepared once (its keys known without repeats) is applied
        again and again, nearly always in that case; then no dict of what went and
        came needs to be made and compared, which ``swap`` does per call."""
        data, seq = self._data, self._seq
        # What a failure half way must put back, read as the check reads the keys
        # (a subscript fails for a key that is not there): each key is hashed as
        # few times as can be, and a fact's hash is a call of its own.
        kept: tuple[tuple[V, int], ...] = ()
        writes = 0
        try:
            for key in gone:
                kept += ((data[key], seq[key]),)
                writes += 1
        except KeyError:
            return False
        for key in fresh:
            if key in data:
                return False
        first = nxt = self._next
        try:
            for key in gone:
                del data[key]
                del seq[key]
            for key in came:
                data[key] = value
                seq[key] = nxt
                nxt += 1
        except BaseException:
            # every key of gone back as it was, every fresh key of came away,
            # wherever the failure came (plain tuples: no iteration of their own)
            lost = dict(zip(gone[:], kept, strict=True))
            self._put_back({k: None for k in came[:] if k not in lost}, {}, lost)
            raise
        self.writes += writes + nxt - first
        self._next = nxt
        return True

    def _put_back(
        self, new: dict[K, None], overwritten: dict[K, V], lost: dict[K, tuple[V, int]]
    ) -> None:
        """Undo a :meth:`swap` that failed half way, insertion order included."""
        data, seq = self._data, self._seq
        self.writes += 1
        for key in new:
            data.pop(key, None)
            seq.pop(key, None)
        for key, old in overwritten.items():
            data[key] = old
        for key, (old, place) in lost.items():
            data[key] = old
            seq[key] = place
        if lost:
            self._data = {k: data[k] for k in sorted(data, key=seq.__getitem__)}

    def clear(self) -> None:
        for key in list(self._data):
            self.delete(key)

    # ------------------------------------------------------------------ the log

    def mark(self) -> int:
        """A point to undo back to, or to report changes since."""
        return len(self._log)

    def undo(self, mark: int) -> None:
        """Put the table back as it was at ``mark``, insertion order included."""
        put_back = False
        self.writes += 1
        while len(self._log) > mark:
            key, old, seq = self._log.pop()
            if isinstance(old, _Missing):
                del self._data[key]
                del self._seq[key]
                continue
            if key not in self._data:
                self._seq[key] = seq
                put_back = True
            self._data[key] = old
        if put_back:
            self._data = {k: self._data[k] for k in sorted(self._data, key=self._seq.__getitem__)}

    def changes_since(self, mark: int) -> tuple[dict[K, V], dict[K, V]]:
        """``(now, before)``: the entries that differ, as they are now (keys still
        there) and as they were at ``mark`` (keys that were there)."""
        log = self._log
        if len(log) == mark:  # most changes leave most tables alone
            return {}, {}
        first: dict[K, V | _Missing] = {}
        for i in range(mark, len(log)):
            key, old, _ = log[i]
            if key not in first:
                first[key] = old
        now: dict[K, V] = {}
        before: dict[K, V] = {}
        for key, old in first.items():
            new = self._data.get(key, MISSING)
            if new == old:
                continue
            if not isinstance(new, _Missing):
                now[key] = new
            if not isinstance(old, _Missing):
                before[key] = old
        return now, before

    def forget_log(self) -> None:
        """Keep the table as it is; nothing before now can be undone."""
        self._log.clear()
