"""Things registered once under a name: the components (by model identifier) and the systems (by name)."""

from .cosim.suggest import did_you_mean


class Registry:
    """Items in registration order under ``key(item)``; ``kind`` names them in messages."""

    def __init__(self, kind, key, hint=""):
        self.kind, self.key, self.hint, self._items = kind, key, hint, {}

    def register(self, item):
        """Add ``item``; return it. Another item under the same name is refused."""
        known = self._items.get(self.key(item))
        if known is not None and known is not item:
            raise ValueError(f"a {self.kind} {self.key(item)!r} is already registered")
        self._items[self.key(item)] = item
        return item

    def unregister(self, name):
        self._items.pop(name, None)

    def get(self, name):
        """The item, or ValueError listing the known names."""
        try:
            return self._items[name]
        except KeyError:
            raise ValueError(f"no {self.kind} {name!r}; {self.kind}s: {', '.join(self._items)}{self.hint}"
                             + did_you_mean(name, self._items)) from None

    def find(self, name):
        """The item, or None."""
        return self._items.get(name)

    def registered(self):
        """Every item, in registration order."""
        return list(self._items.values())
