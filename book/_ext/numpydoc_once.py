"""Sphinx extension: numpydoc's docstring template compiled once per build, not once per docstring.

numpydoc's ``get_doc_object`` builds a Jinja environment and compiles
``numpydoc_docstring.rst`` for every docstring it renders (about 5 000 in this book's
API reference). :func:`get_doc_object` below lets numpydoc do that for the first
docstring of a build, keeps the compiled template and hands it to every later call;
the rendered text is the same, only the repeated compilation is gone. It is installed
through numpydoc's own hook (the module-level ``get_doc_object`` of
``numpydoc.numpydoc``, which ``numpydoc.numpydoc.setup`` sets too).
"""

from __future__ import annotations

from typing import Any

from numpydoc import docscrape, docscrape_sphinx
from numpydoc import numpydoc as _numpydoc

#: The compiled template per builder (one build has one builder).
_TEMPLATES: dict[int, Any] = {}


def get_doc_object(obj, what=None, doc=None, config=None, builder=None):
    """numpydoc's :func:`numpydoc.docscrape_sphinx.get_doc_object`, with the template of
    the first call reused by the later calls of the same builder."""
    config = {} if config is None else config
    template = _TEMPLATES.get(id(builder))
    if template is None:  # numpydoc compiles it and leaves it in config["template"]
        result = docscrape_sphinx.get_doc_object(obj, what, doc, config, builder)
        _TEMPLATES[id(builder)] = config["template"]
        return result
    config["template"] = template
    return docscrape.get_doc_object(
        obj,
        what=what,
        doc=doc,
        config=config,
        class_doc=docscrape_sphinx.SphinxClassDoc,
        func_doc=docscrape_sphinx.SphinxFunctionDoc,
        obj_doc=docscrape_sphinx.SphinxObjDoc,
    )


def setup(app) -> dict:
    """Install :func:`get_doc_object` as numpydoc's (numpydoc must be loaded first)."""
    app.setup_extension("numpydoc")
    _numpydoc.get_doc_object = get_doc_object
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
