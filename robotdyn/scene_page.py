"""A meshcat scene as one standalone HTML page, compact: shared meshes once, compressed.

meshcat scenes are sequences of msgpack commands (``set_object``, ``set_transform``, ``set_animation``...). A
page holds meshcat's viewer JavaScript inlined and the commands, applied in order when it opens (offline: no
server, no network). Every object carries its own copy of its mesh file, so a robot with four identical wheels
would carry the wheel four times, and an animation repeats similar keyframes: stored plainly, a large robot's page
ran to 35 MB. :func:`pack_scene` stores every distinct segment of the commands once (commands are split around
their large payloads, so a mesh shared by several links is stored once) and deflate-compresses the lot; the page
unpacks it with the browser's built-in ``DecompressionStream`` (Chrome 80, Firefox 113, Safari 16.4 or later)
before drawing. :func:`page_commands` reads the commands of a page back (tests, tools).
"""

from __future__ import annotations

import base64
import html
import struct
import zlib
from pathlib import Path


def _meshcat():
    """Import meshcat lazily, without its pyzmq DeprecationWarning."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import meshcat
        import meshcat.animation
        import meshcat.geometry
        import meshcat.servers.tree
    return meshcat


SHARED_MIN_BYTES = 1024
"""Payloads (mesh files, vertex arrays) at least this long are stored once per page, however many objects use them."""


def _payloads(obj, out: list) -> None:
    """Byte strings and long text inside a decoded meshcat command (mesh file contents, typed arrays)."""
    if isinstance(obj, dict):
        for value in obj.values():
            _payloads(value, out)
    elif isinstance(obj, (list, tuple)):
        for value in obj:
            _payloads(value, out)
    elif isinstance(obj, (bytes, bytearray)) and len(obj) >= SHARED_MIN_BYTES:
        out.append(bytes(obj))
    elif isinstance(obj, str) and len(obj) >= SHARED_MIN_BYTES:
        out.append(obj.encode("utf-8"))
    elif hasattr(obj, "data") and isinstance(getattr(obj, "data"), (bytes, bytearray)):  # msgpack ext (typed array)
        if len(obj.data) >= SHARED_MIN_BYTES:
            out.append(bytes(obj.data))


def pack_scene(commands: list[bytes]) -> bytes:
    """The scene's msgpack commands in a page's compact form: every distinct segment once, then each command as
    a list of segment indices, zlib-compressed.

    A command is split around its large payloads (:data:`SHARED_MIN_BYTES`), so that a mesh drawn by several links
    (four identical wheels) is stored once; concatenating a command's segments gives back its bytes exactly.
    Layout before compression (little-endian uint32): number of segments, their lengths, their bytes; number of
    commands, then for each its number of segments and their indices.
    """
    import umsgpack

    index: dict[bytes, int] = {}
    segments: list[bytes] = []

    def seg(b: bytes) -> int:
        if b not in index:
            index[b] = len(segments)
            segments.append(b)
        return index[b]

    table = []
    for cmd in commands:
        big: list[bytes] = []
        try:
            _payloads(umsgpack.unpackb(cmd), big)
        except Exception:  # not ours to understand: stored whole
            big = []
        parts, pos = [], 0
        for payload in sorted(set(big), key=lambda b: cmd.find(b)):
            at = cmd.find(payload, pos)
            if at < 0:
                continue
            if at > pos:
                parts.append(seg(cmd[pos:at]))
            parts.append(seg(payload))
            pos = at + len(payload)
        if pos < len(cmd) or not parts:
            parts.append(seg(cmd[pos:]))
        table.append(parts)
    out = [struct.pack("<I", len(segments)), struct.pack(f"<{len(segments)}I", *map(len, segments)), *segments,
           struct.pack("<I", len(table))]
    for parts in table:
        out.append(struct.pack(f"<{len(parts) + 1}I", len(parts), *parts))
    return zlib.compress(b"".join(out), 9)


def unpack_scene(packed: bytes) -> list[bytes]:
    """The commands of :func:`pack_scene`'s output, in order (what the page's script does in the browser)."""
    buf = zlib.decompress(packed)
    (n,), o = struct.unpack_from("<I", buf, 0), 4
    lens = struct.unpack_from(f"<{n}I", buf, o)
    o += 4 * n
    segments = []
    for k in lens:
        segments.append(buf[o:o + k])
        o += k
    (count,) = struct.unpack_from("<I", buf, o)
    o += 4
    out = []
    for _ in range(count):
        (k,) = struct.unpack_from("<I", buf, o)
        parts = struct.unpack_from(f"<{k}I", buf, o + 4)
        o += 4 * (k + 1)
        out.append(b"".join(segments[i] for i in parts))
    return out


def page_commands(page: str) -> list[bytes]:
    """The scene commands a standalone page (:meth:`Viewer.static_html`) applies, in order."""
    start = page.index('var robotdyn_scene = "') + len('var robotdyn_scene = "')
    return unpack_scene(base64.b64decode(page[start:page.index('"', start)]))


def static_page(commands: list[bytes], title: str = "robotdyn") -> str:
    """A standalone HTML page: meshcat's viewer JavaScript inlined and the scene's commands applied in order.

    The commands are stored compactly (:func:`pack_scene`: shared payloads once, deflate-compressed) and unpacked
    in the browser with its built-in ``DecompressionStream`` before the first frame is drawn (a headless browser's
    screenshot sees the complete scene). ``page.html#t=SECONDS`` opens an animation paused at that time.

    (meshcat's own script, 850 kB, stays inlined as it is: unpacked the same way and inserted as a script element,
    it compressed to 290 kB, but headless Chromium's virtual time then stalled on pages holding two such frames.)"""
    mc = _meshcat()
    js = (Path(mc.__file__).parent / "viewer" / "dist" / "main.min.js").read_text(encoding="utf-8")
    js = js.replace("</script", "<\\/script")
    scene = base64.b64encode(pack_scene(commands)).decode("ascii")
    return f"""<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body {{ margin: 0; }} #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var robotdyn_scene = "{scene}";
{_UNPACK_JS}
robotdyn_unpack(robotdyn_scene).then(function (commands) {{
  for (var i = 0; i < commands.length; i++) viewer.handle_command_bytearray(commands[i]);
  console.log("robotdyn: applied " + commands.length + " scene commands");
  var robotdyn_t = /[#&]t=([-+0-9.eE]+)/.exec(location.hash);
  if (robotdyn_t && viewer.animator.actions.length > 0) {{
    viewer.animator.pause();
    viewer.animator.seek(parseFloat(robotdyn_t[1]));
    viewer.animator.display_progress(parseFloat(robotdyn_t[1]));
    console.log("robotdyn: animation paused at t = " + parseFloat(robotdyn_t[1]) + " s");
  }}
}}).catch(function (err) {{
  console.log("robotdyn: cannot unpack the scene: " + err);
  document.body.insertAdjacentHTML("afterbegin", "<p>robotdyn: this browser cannot unpack the scene (" + err +
    "); a browser with DecompressionStream (Chrome 80, Firefox 113, Safari 16.4 or later) is needed.</p>");
}});
</script>
</body>
</html>
"""


_UNPACK_JS = """// robotdyn_inflate: base64 -> bytes, zlib-inflated by the browser's DecompressionStream
async function robotdyn_inflate(b64) {
  var raw = atob(b64), bytes = new Uint8Array(raw.length);
  for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}
// robotdyn_unpack: the scene's commands from pack_scene's layout (shared segments, then each command's indices)
async function robotdyn_unpack(b64) {
  var buf = await robotdyn_inflate(b64);
  var view = new DataView(buf.buffer, buf.byteOffset, buf.byteLength), o = 0;
  function u32() { var x = view.getUint32(o, true); o += 4; return x; }
  var n = u32(), lens = [], segments = [], commands = [];
  for (var s = 0; s < n; s++) lens.push(u32());
  for (var s = 0; s < n; s++) { segments.push(buf.subarray(o, o + lens[s])); o += lens[s]; }
  var count = u32();
  for (var c = 0; c < count; c++) {
    var k = u32(), parts = [], total = 0;
    for (var p = 0; p < k; p++) { var seg = segments[u32()]; parts.push(seg); total += seg.length; }
    var cmd = new Uint8Array(total), at = 0;
    for (var p = 0; p < k; p++) { cmd.set(parts[p], at); at += parts[p].length; }
    commands.push(cmd);
  }
  return commands;
}"""


__all__ = ["static_page", "pack_scene", "unpack_scene", "page_commands", "SHARED_MIN_BYTES"]
