"""A meshcat scene as one standalone HTML page, compact: shared meshes once, compressed.

meshcat scenes are sequences of msgpack commands (``set_object``, ``set_transform``, ``set_animation``...). A
page holds meshcat's viewer JavaScript inlined and the commands, applied in order when it opens (offline: no
server, no network). Every object carries its own copy of its mesh file, so a robot with four identical wheels
would carry the wheel four times, and an animation repeats similar keyframes: stored plainly, a large robot's page
ran to 35 MB. :func:`pack_scene` stores every distinct segment of the commands once (commands are split around
their large payloads, so a mesh shared by several links is stored once) and zlib-compresses the lot; the page
inflates it with its own small synchronous decoder before drawing (no browser API beyond ``atob`` is needed).
:func:`page_commands` reads the commands of a page back (tests, tools).
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

    Args:
        commands: The scene's msgpack commands, in order.

    Returns:
        The zlib-compressed bytes of the compact form.
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
    """The commands of :func:`pack_scene`'s output, in order (what the page's script does in the browser).

    Args:
        packed: The output of :func:`pack_scene`.

    Returns:
        The msgpack commands, one ``bytes`` each.
    """
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
    """The scene commands a standalone page (:meth:`Viewer.static_html`) applies, in order.

    Args:
        page: A page's HTML text (:meth:`~robotdyn.interfaces.viewer.Viewer.static_html`).

    Returns:
        The msgpack commands, one ``bytes`` each.
    """
    start = page.index('var robotdyn_scene = "') + len('var robotdyn_scene = "')
    return unpack_scene(base64.b64decode(page[start:page.index('"', start)]))


def static_page(commands: list[bytes], title: str = "robotdyn") -> str:
    """A standalone HTML page: meshcat's viewer JavaScript inlined and the scene's commands applied in order.

    The commands are stored compactly (:func:`pack_scene`: shared payloads once, zlib-compressed) and unpacked
    synchronously by the page's own inflate (:data:`_UNPACK_JS`, after Mark Adler's ``puff.c``) before the first
    frame is drawn, so a headless browser's screenshot sees the complete scene. (The browser's asynchronous
    ``DecompressionStream`` was tried first: headless Chromium's virtual time then stalled, now and then, on pages
    holding several such frames.) ``page.html#t=SECONDS`` opens an animation paused at that time.

    Args:
        commands: The scene's msgpack commands, in order.
        title: The page's title.

    Returns:
        The HTML text.
    """
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
var robotdyn_commands = robotdyn_unpack(robotdyn_scene);
for (var i = 0; i < robotdyn_commands.length; i++) viewer.handle_command_bytearray(robotdyn_commands[i]);
console.log("robotdyn: applied " + robotdyn_commands.length + " scene commands");
// page.html#t=SECONDS opens an animation paused at that time
var robotdyn_t = /[#&]t=([-+0-9.eE]+)/.exec(location.hash);
if (robotdyn_t && viewer.animator.actions.length > 0) {{
  viewer.animator.pause();
  viewer.animator.seek(parseFloat(robotdyn_t[1]));
  viewer.animator.display_progress(parseFloat(robotdyn_t[1]));
  console.log("robotdyn: animation paused at t = " + parseFloat(robotdyn_t[1]) + " s");
}}
</script>
</body>
</html>
"""


_UNPACK_JS = """// robotdyn_inflate: zlib (RFC 1950/1951) inflate, synchronous, after Mark Adler's puff.c
function robotdyn_inflate(data) {
  var out = new Uint8Array(Math.max(1 << 16, 4 * data.length)), n = 0, pos = 2, buf = 0, cnt = 0;
  function need(k) {
    if (n + k > out.length) { var o = new Uint8Array(Math.max(2 * out.length, n + k)); o.set(out.subarray(0, n)); out = o; }
  }
  function bits(k) {
    while (cnt < k) { if (pos >= data.length) throw new Error("inflate: unexpected end of data"); buf |= data[pos++] << cnt; cnt += 8; }
    var v = buf & ((1 << k) - 1); buf >>>= k; cnt -= k; return v;
  }
  function table(lengths, start, count) {
    var counts = new Uint16Array(16), offs = new Uint16Array(16), syms = new Uint16Array(count);
    for (var i = 0; i < count; i++) counts[lengths[start + i]]++;
    counts[0] = 0;
    for (var i = 1; i < 16; i++) offs[i] = offs[i - 1] + counts[i - 1];
    for (var i = 0; i < count; i++) if (lengths[start + i]) syms[offs[lengths[start + i]]++] = i;
    return { counts: counts, syms: syms };
  }
  function decode(t) {
    var code = 0, first = 0, index = 0;
    for (var len = 1; len < 16; len++) {
      code |= bits(1);
      var c = t.counts[len];
      if (code - c < first) return t.syms[index + (code - first)];
      index += c; first += c; first <<= 1; code <<= 1;
    }
    throw new Error("inflate: bad code");
  }
  var LBASE = [3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258];
  var LEXT = [0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0];
  var DBASE = [1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1025, 1537, 2049, 3073,
               4097, 6145, 8193, 12289, 16385, 24577];
  var DEXT = [0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13];
  var ORDER = [16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15];
  var fixed = null;
  if ((data[0] & 15) !== 8 || ((data[0] << 8) | data[1]) % 31 !== 0 || (data[1] & 32)) throw new Error("inflate: not a zlib stream");
  for (var last = 0; !last;) {
    last = bits(1);
    var type = bits(2), lit, dist;
    if (type === 0) {
      buf = 0; cnt = 0;  // to a byte boundary (fewer than 8 bits are ever held)
      var len = data[pos] | (data[pos + 1] << 8);
      if (((data[pos + 2] | (data[pos + 3] << 8)) ^ 0xffff) !== len) throw new Error("inflate: bad stored block");
      pos += 4;
      if (pos + len > data.length) throw new Error("inflate: unexpected end of data");
      need(len); out.set(data.subarray(pos, pos + len), n); n += len; pos += len;
      continue;
    } else if (type === 1) {
      if (!fixed) {
        var l = new Uint8Array(320);
        for (var i = 0; i < 288; i++) l[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
        for (var i = 288; i < 320; i++) l[i] = 5;
        fixed = [table(l, 0, 288), table(l, 288, 30)];
      }
      lit = fixed[0]; dist = fixed[1];
    } else if (type === 2) {
      var nlen = bits(5) + 257, ndist = bits(5) + 1, ncode = bits(4) + 4, lengths = new Uint8Array(320);
      for (var i = 0; i < ncode; i++) lengths[ORDER[i]] = bits(3);
      var lencode = table(lengths, 0, 19);
      lengths = new Uint8Array(320);
      for (var i = 0; i < nlen + ndist;) {
        var sym = decode(lencode);
        if (sym < 16) { lengths[i++] = sym; continue; }
        var val = 0, rep;
        if (sym === 16) { if (i === 0) throw new Error("inflate: repeat with no length"); val = lengths[i - 1]; rep = 3 + bits(2); }
        else if (sym === 17) rep = 3 + bits(3);
        else rep = 11 + bits(7);
        if (i + rep > nlen + ndist) throw new Error("inflate: too many lengths");
        while (rep--) lengths[i++] = val;
      }
      lit = table(lengths, 0, nlen); dist = table(lengths, nlen, ndist);
    } else {
      throw new Error("inflate: bad block type");
    }
    for (;;) {
      var sym = decode(lit);
      if (sym < 256) { need(1); out[n++] = sym; continue; }
      if (sym === 256) break;
      sym -= 257;
      if (sym >= 29) throw new Error("inflate: bad length code");
      var len = LBASE[sym] + bits(LEXT[sym]);
      var ds = decode(dist);
      if (ds >= 30) throw new Error("inflate: bad distance code");
      var d = DBASE[ds] + bits(DEXT[ds]);
      if (d > n) throw new Error("inflate: distance too far back");
      need(len);
      for (var k = 0; k < len; k++, n++) out[n] = out[n - d];
    }
  }
  return out.subarray(0, n);
}
// robotdyn_unpack: the scene's commands from pack_scene's layout (shared segments, then each command's indices)
function robotdyn_unpack(b64) {
  var raw = atob(b64), bytes = new Uint8Array(raw.length);
  for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  var buf = robotdyn_inflate(bytes);
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
