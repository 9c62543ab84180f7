"""Problem kinds: one module per kind, each calling :func:`orientviz.io.registry.register_kind`.

Modules whose name starts with ``_`` are helpers, not kinds. :func:`orientviz.io.registry.get_kind`
imports ``orientviz.io.kinds.<kind>`` on first use.
"""
