"""Named plug-ins of one kind (firmwares, sensors, local controllers, planners, experiments...).

A package registers its built-ins where it defines them; a third party adds its own from its
module with :meth:`Registry.register`, and the CLI takes its choices and its check from the same
registry. Modelled on nav2's plug-in names and dm_control's named entities.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Generic, TypeVar

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(Generic[T]):
    """Plug-ins of one ``kind`` by name, kept in registration order.

    Args:
        kind: what the plug-ins are, as the user's option names it (``"--firmware"``), used in
            the one-line refusal of an unknown name.
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T] = {}

    def register(self, name: str, entry: T | None = None, *, replace: bool = False):
        """Add ``entry`` under ``name``; without ``entry``, a decorator that adds what it wraps.

        Args:
            name: the plug-in's name: lower case, digits, ``-`` and ``_``.
            entry: the factory or class; returned unchanged.
            replace: allow a name that is already taken (else ValueError).
        """
        if not name or not all(c.islower() or c.isdigit() or c in "-_" for c in name):
            raise ValueError(
                f"{self.kind} name {name!r}: use lower-case letters, digits, '-' and '_'"
            )
        if entry is None:
            return lambda wrapped: self.register(name, wrapped, replace=replace)
        if name in self._entries and not replace:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._entries[name] = entry
        return entry

    def get(self, name: str) -> T:
        """The entry of ``name``; ValueError naming the option and the allowed names."""
        try:
            return self._entries[name]
        except KeyError:
            raise ValueError(f"{self.kind} {name!r}: must be one of {self.choices()}") from None

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._entries)

    def choices(self) -> str:
        """The names as a help text lists them: ``a, b or c``."""
        names = self.names()
        return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1]

    def unregister(self, name: str) -> None:
        """Remove ``name`` (a test's plug-in after the test); KeyError if absent."""
        del self._entries[name]

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)
