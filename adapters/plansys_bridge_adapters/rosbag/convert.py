"""Bridge a ROS 1 bag (or any bag) into a ROS 2 MCAP bag, streaming.

``python -m plansys_bridge_adapters.rosbag.convert SRC DST [--topic T ...]`` copies
the chosen topics (default: every topic whose type ROS 2 Humble knows) into a new
rosbag2 directory with MCAP storage, converting ROS 1 messages to their ROS 2 types
on the way (the bridging a ROS 1 robot needs to be replayed by ROS 2 tools). One
message is in memory at a time. A topic whose type cannot be converted is an error
naming it, unless ``--skip-unconvertible`` leaves it out (and says so).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

from .errors import BagError, BagTypeError
from .reader import BagReader, ros2_typestore


@dataclass
class ConversionReport:
    """What :func:`convert_to_ros2` wrote and what it left out."""

    destination: Path
    counts: dict[str, int] = field(default_factory=dict)
    """Messages written per topic."""
    skipped: dict[str, str] = field(default_factory=dict)
    """Topic -> why it was left out."""


def convert_to_ros2(
    source: str | Path,
    destination: str | Path,
    topics: Sequence[str] | None = None,
    *,
    skip_unconvertible: bool = False,
) -> ConversionReport:
    """Copy ``topics`` of ``source`` into a new ROS 2 MCAP bag at ``destination``.

    On any error the partly written destination is removed, so a failed conversion
    never leaves a bag that looks complete.
    """
    dst = Path(destination)
    report = ConversionReport(dst)
    store = ros2_typestore()
    with BagReader(source) as bag:
        wanted = list(topics) if topics is not None else sorted(bag.topics)
        chosen: list[str] = []
        for topic in wanted:
            try:
                bag.ros2_msgtype(topic)
            except BagTypeError as exc:
                if not skip_unconvertible:
                    raise
                report.skipped[topic] = exc.message
                continue
            chosen.append(topic)
        if dst.exists():
            raise BagError("destination exists already; not overwriting", dst)
        try:
            with Writer(dst, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP) as w:
                conns = {
                    topic: w.add_connection(topic, bag.ros2_msgtype(topic), typestore=store)
                    for topic in chosen
                }
                if chosen:
                    for msg in bag.messages(chosen):
                        w.write(conns[msg.topic], msg.bag_time_ns, msg.cdr)
                        report.counts[msg.topic] = report.counts.get(msg.topic, 0) + 1
        except WriterError as exc:
            shutil.rmtree(dst, ignore_errors=True)
            raise BagError(f"cannot write ROS 2 bag: {exc}", dst) from exc
        except BaseException:
            shutil.rmtree(dst, ignore_errors=True)
            raise
    return report


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("source", type=Path, help="ROS 1 .bag, ROS 2 .mcap/.db3 or rosbag2 folder")
    parser.add_argument("destination", type=Path, help="rosbag2 folder to create (MCAP)")
    parser.add_argument("--topic", action="append", help="topic to copy (repeatable; default all)")
    parser.add_argument(
        "--skip-unconvertible",
        action="store_true",
        help="leave out topics whose type ROS 2 Humble does not know instead of failing",
    )
    args = parser.parse_args(argv)
    try:
        report = convert_to_ros2(
            args.source, args.destination, args.topic, skip_unconvertible=args.skip_unconvertible
        )
    except BagError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for topic, count in sorted(report.counts.items()):
        print(f"{topic}: {count} messages")
    for topic, why in sorted(report.skipped.items()):
        print(f"{topic}: skipped ({why})")
    print(f"wrote {report.destination}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
