"""One shape for every extension: an entry-point group, a base class, a settings model.

plansys-bridge is extended in four places, and each works the same way:

==================  ===================================  =======================================
kind                entry-point group                    base class
==================  ===================================  =======================================
performers          ``plansys_bridge.performers``        ``performers.base.ActionPerformer``
solvers             ``plansys_bridge.solvers``           ``planning.solvers.base.Solver``
transports          ``plansys_bridge.transports``        ``hub.transport_kinds.TransportKind``
sensing sources     ``plansys_bridge.sensing_sources``   ``sensing.source.SensingSource``
==================  ===================================  =======================================

A plugin is a subclass of its kind's base class, registered by name in the group
(``[project.entry-points."plansys_bridge.performers"] gripper = "pkg.mod:Gripper"``),
that declares its mission-file settings as a pydantic model on the class::

    class Gripper(ActionPerformer):
        class Settings(PluginSettings):
            force: float = Field(10.0, gt=0)

The mission loader validates every section through that model before anything
starts, so a typo or a wrong type is one error naming the file, line, column and
key path (``mission.yaml:12:7: performers[1].force: ...``). The project's own
plugins are registered through the same entry points as third-party ones.

A class is imported only when a mission names it: a missing optional dependency of
one plugin (pymavlink for ``mavlink``) never breaks the others, and is reported as
one error naming the extra to install.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
from collections.abc import Mapping, Sequence
from contextvars import ContextVar
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Generic, Self, TypeVar

from pydantic import (
    BaseModel,
    ConfigDict,
    ModelWrapValidatorHandler,
    ValidationError,
    ValidationInfo,
    model_validator,
)

from plansys_bridge.errors import ConfigError, PluginError

__all__ = [
    "GROUPS",
    "DirectSettings",
    "NoSettings",
    "PluginRegistry",
    "PluginSettings",
    "key_path",
    "settings_model",
    "validate_settings",
    "validation_message",
]

GROUPS: dict[str, str] = {
    "performers": "plansys_bridge.performers",
    "solvers": "plansys_bridge.solvers",
    "transports": "plansys_bridge.transports",
    "sensing_sources": "plansys_bridge.sensing_sources",
}
"""Extension kind -> its entry-point group."""

# Top-level module of an optional dependency -> the extra that installs it.
EXTRA_FOR_MODULE = {
    "pymavlink": "mavlink",
    "can": "can",
    "cantools": "can",
    "rosbags": "rosbag",
    "mcap": "rosbag",
    "cyclonedds": "dds",
    "unified_planning": "planners",
}


class PluginSettings(BaseModel):
    """Base of a plugin's ``Settings``: unknown keys are errors, types are not coerced
    (YAML's ``"5"`` is not a number, ``true`` is not 1), NaN and infinity are refused,
    and the validated settings cannot change under the running plugin."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


class DirectSettings(PluginSettings):
    """Settings that code also builds directly (``FaultPlan(die_rate=0.1)``): a bad
    value there is the project's ConfigError naming the field, as in a mission file,
    not pydantic's ValidationError.

    Only a validation without a context is direct construction: the mission loader
    (:func:`validate_settings`) always passes one, so its ValidationError, which keeps
    the whole key path and the file:line:col, reaches it untouched, nested models
    included."""

    @model_validator(mode="wrap")
    @classmethod
    def _config_error_when_built_directly(
        cls, data: Any, handler: ModelWrapValidatorHandler[Self], info: ValidationInfo
    ) -> Self:
        if info.context is not None or _BUILDING_DIRECTLY.get():
            # the loader's validation, or a model nested in one built directly: the
            # outermost one names the whole key path
            return handler(data)
        token = _BUILDING_DIRECTLY.set(True)
        try:
            return handler(data)
        except ValidationError:
            # again through validate_settings for the message a mission file gets;
            # it raises the ConfigError (a bad value fails every time)
            validate_settings(cls, data)
            raise
        finally:
            _BUILDING_DIRECTLY.reset(token)


_BUILDING_DIRECTLY: ContextVar[bool] = ContextVar("plansys_bridge_building_settings", default=False)


class NoSettings(PluginSettings):
    """The settings of a plugin that has none: any key is an error."""


T = TypeVar("T")
M = TypeVar("M", bound=BaseModel)


@functools.cache
def _entry_points(group: str) -> dict[str, EntryPoint]:
    """The group's entry points, read once (scanning the installed packages is slow)."""
    return {ep.name: ep for ep in entry_points(group=group)}


class PluginRegistry(Generic[T]):
    """The plugins of one kind: names from the entry-point group, classes on demand.

    ``builtin`` lists the project's own plugins with the same ``module:Class`` text as
    its entry points; it is consulted only for a name the installed metadata does not
    have (an editable install made before the plugin was added), never instead of it.
    """

    def __init__(
        self,
        group: str,
        base: type[Any],
        what: str,
        *,
        builtin: Mapping[str, str] | None = None,
    ) -> None:
        self.group = group
        self.base = base
        self.what = what
        self.builtin: dict[str, str] = dict(builtin or {})
        self._loaded: dict[str, type[T]] = {}

    def entry_points(self) -> dict[str, EntryPoint]:
        return _entry_points(self.group)

    def names(self) -> list[str]:
        """Every registered name: the project's own first (in their order), then others."""
        registered = self.entry_points()
        return [*self.builtin, *sorted(n for n in registered if n not in self.builtin)]

    def reference(self, name: str) -> str | None:
        """The ``module:Class`` text ``name`` is registered with (None: not registered)."""
        ep = self.entry_points().get(name)
        return ep.value if ep is not None else self.builtin.get(name)

    def cache_clear(self) -> None:
        self._loaded.clear()

    def load(self, name: str) -> type[T]:
        """The class registered as ``name``; PluginError if unknown or not importable."""
        cls = self._loaded.get(name)
        if cls is None:
            cls = self._import(name)
            self._loaded[name] = cls
        return cls

    def _import(self, name: str) -> type[T]:
        reference = self.reference(name)
        if reference is None:
            known = ", ".join(self.names()) or "none installed"
            raise PluginError(f"unknown {self.what} {name!r} (known: {known})")
        module_name, _, attr = reference.partition(":")
        try:
            obj: Any = importlib.import_module(module_name)
            for part in attr.split(".") if attr else ():
                obj = getattr(obj, part)
        except ModuleNotFoundError as exc:
            raise PluginError(self._missing_module(name, reference, exc)) from exc
        except (ImportError, AttributeError) as exc:
            raise PluginError(
                f"{self.what} {name!r} could not be loaded from {reference}: {exc}"
            ) from exc
        if not (isinstance(obj, type) and issubclass(obj, self.base)):
            raise PluginError(
                f"{self.what} {name!r} ({reference}) is not {_article(self.base.__name__)} "
                f"{self.base.__name__} subclass"
            )
        return obj

    def _missing_module(self, name: str, reference: str, exc: ModuleNotFoundError) -> str:
        """Why ``reference`` did not import: a module that is not there although its
        package is installed (a misspelt entry point, or a bad import inside the
        plugin) is named as such; only a package that is not installed at all is an
        optional dependency to install, with the extra that provides it if it is ours."""
        missing_name = exc.name or ""
        missing = missing_name.split(".")[0]
        if _installed(missing):
            module = reference.partition(":")[0]
            misspelt = module == missing_name or module.startswith(missing_name + ".")
            why = "is the entry point misspelt?" if misspelt else f"{module} imports it"
            return (
                f"{self.what} {name!r} points at {reference}: "
                f"no module named {missing_name!r} ({why})"
            )
        extra = EXTRA_FOR_MODULE.get(missing)
        hint = (
            f"install it with: pip install 'plansys-bridge[{extra}]'"
            if extra
            else f"install the package that provides {missing!r}"
        )
        return f"{self.what} {name!r} needs the optional dependency {missing!r}; {hint}"


def _article(word: str) -> str:
    return "an" if word[:1].upper() in "AEIOU" else "a"


def _installed(module: str) -> bool:
    """Is the top-level ``module`` importable (its package installed)?"""
    try:
        return bool(module) and importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def settings_model(cls: type) -> type[BaseModel] | None:
    """The ``Settings`` model a plugin class declares (None: an old-style plugin)."""
    model = getattr(cls, "Settings", None)
    return model if isinstance(model, type) and issubclass(model, BaseModel) else None


def key_path(loc: Sequence[int | str]) -> str:
    """``("performers", 1, "bus", "interface")`` -> ``performers[1].bus.interface``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def join_key(prefix: str, rest: str) -> str:
    """``performers[1]`` + ``bus.interface``; ``rest`` may start with an index."""
    if not prefix or not rest:
        return prefix or rest
    return prefix + rest if rest.startswith("[") else f"{prefix}.{rest}"


def validation_message(error: Mapping[str, Any]) -> str:
    """One pydantic error as a sentence a mission author understands."""
    kind = error.get("type", "")
    if kind == "extra_forbidden":
        return "unknown key"
    if kind == "missing":
        return "missing: this key is required"
    message = str(error.get("msg", "")).removeprefix("Value error, ")
    value = error.get("input")
    if kind not in ("value_error", "assertion_error") and isinstance(
        value, str | int | float | bool | type(None)
    ):
        message = f"{message}, got {value!r}"
    return message


def _loc(error: Mapping[str, Any]) -> tuple[int | str, ...]:
    """The error's place without pydantic's union and tagged-union branch names."""
    return tuple(p for p in error.get("loc", ()) if not (isinstance(p, str) and "[" in p))


def validate_settings(
    model: type[M],
    data: object,
    *,
    key: str = "",
    known: Sequence[str] = (),
    context: Mapping[str, Any] | None = None,
) -> M:
    """``data`` validated through ``model``; the first problem is a ConfigError naming
    its key path below ``key``. An unknown key lists the known ones (``known`` adds
    keys handled beside the model, e.g. a performer's ``name``)."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ConfigError(f"must be a mapping of settings, got {data!r}", key=key or None)
    try:
        return model.model_validate(dict(data), context=dict(context or {}))
    except ValidationError as exc:
        error = exc.errors()[0]
        loc = _loc(error)
        message = validation_message(error)
        if error["type"] == "extra_forbidden":
            allowed = sorted({*_field_names(model, loc[:-1]), *(known if len(loc) == 1 else ())})
            message = f"unknown key (allowed: {', '.join(allowed) or 'none'})"
        raise ConfigError(message, key=join_key(key, key_path(loc)) or None) from exc


def _field_names(model: type[BaseModel], loc: Sequence[int | str]) -> list[str]:
    """The field names of the (nested) model at ``loc``, for "allowed: ..." lists."""
    current: Any = model
    for part in loc:
        if isinstance(part, int):
            continue
        field = getattr(current, "model_fields", {}).get(part)
        if field is None:
            return []
        current = _model_in(field.annotation)
    fields = getattr(current, "model_fields", None)
    return list(fields) if isinstance(fields, dict) else []


def _model_in(annotation: Any) -> Any:
    """The BaseModel inside ``X``, ``X | None``, ``list[X]``, ``dict[str, X]``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = _model_in(arg)
        if found is not None:
            return found
    return None
