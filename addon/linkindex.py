"""The link feeding an input socket, looked up in an index built once per node tree.

Blender's `NodeSocket.links` is Python that scans every link of the tree (O(links) per call),
so following an n-node chain socket by socket costs O(n²): 0.75 s CPU for used_outputs on an
800-node Math chain. Within `indexed_links()` the first link of each input (as `links[0]`
gives it: the highest multi_input_sort_id, the earlier in the tree's order on a tie) comes
from a dict built once per tree. The scope must not outlive edits of the trees it reads (an
index would hold removed links), so only code that reads trees and edits none opens it.
"""

from __future__ import annotations

import contextlib
import contextvars

# tree pointer -> {to_socket pointer -> link}; None outside indexed_links
_INDEX = contextvars.ContextVar('dacrt_link_index', default=None)


@contextlib.contextmanager
def indexed_links():
    """Within it, first_link reads an index per tree (nested scopes share the outer one)."""
    if _INDEX.get() is not None:
        yield
        return
    token = _INDEX.set({})
    try:
        yield
    finally:
        _INDEX.reset(token)


def first_link(sock):
    """The link sock.links[0] would give for a linked input socket (is_linked true)."""
    index = _INDEX.get()
    if index is None:
        return sock.links[0]
    tree = sock.id_data
    links = index.get(tree.as_pointer())
    if links is None:
        links = index[tree.as_pointer()] = {}
        for link in tree.links:
            key = link.to_socket.as_pointer()
            best = links.get(key)
            if best is None or link.multi_input_sort_id > best.multi_input_sort_id:
                links[key] = link
    link = links.get(sock.as_pointer())
    return sock.links[0] if link is None else link
