"""OPC UA node ids from a tag map, resolved on a connected client.

A tag map names each tag's node in the NodeId string form of OPC UA Part 6, §5.3.1.10:
``ns=<index>;…`` (an index into the server's namespace array, which may change when the
server is reconfigured) or ``nsu=<namespace URI>;…`` (stable: resolved here against the
server's NamespaceArray on every connection).
"""

from __future__ import annotations

from asyncua import Client, ua

__all__ = ["resolve_node_id"]


async def resolve_node_id(client: Client, text: str) -> ua.NodeId:
    """The node id ``text`` (``ns=`` or ``nsu=`` form) on ``client``'s server; ValueError
    naming the id when its namespace URI is not served there."""
    parsed = ua.NodeId.from_string(text)
    uri = getattr(parsed, "NamespaceUri", None)
    if not uri:
        return ua.NodeId(parsed.Identifier, parsed.NamespaceIndex, parsed.NodeIdType)
    namespaces = await client.get_namespace_array()
    if uri not in namespaces:
        raise ValueError(f"node id {text!r}: the server does not serve namespace {uri!r} "
                         f"(it serves {namespaces})")
    return ua.NodeId(parsed.Identifier, namespaces.index(uri), parsed.NodeIdType)
