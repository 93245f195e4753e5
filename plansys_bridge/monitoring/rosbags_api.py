"""The rosbags names the monitoring uses, imported in one place.

rosbags (and numpy, which it depends on) is an optional dependency, the ``rosbag``
extra. Importing it here, once, turns a missing install into one clear
:class:`~plansys_bridge.errors.PluginError` naming the extra, instead of a bare
``ModuleNotFoundError`` from whichever monitoring module was imported first.
"""

from __future__ import annotations

from plansys_bridge.errors import PluginError

try:
    import numpy as np
    from rosbags.highlevel import AnyReader, AnyReaderError
    from rosbags.rosbag2 import ReaderError, StoragePlugin, Writer, WriterError
    from rosbags.serde import SerdeError
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    from rosbags.typesys.store import Typestore
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise PluginError(
        "recording and replaying missions needs rosbags: pip install 'plansys-bridge[rosbag]'"
    ) from exc

__all__ = [
    "AnyReader",
    "AnyReaderError",
    "ReaderError",
    "SerdeError",
    "StoragePlugin",
    "Stores",
    "Typestore",
    "Writer",
    "WriterError",
    "get_types_from_msg",
    "get_typestore",
    "np",
]
