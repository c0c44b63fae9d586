"""OctoMap binary (.bt) files from voxel sets, for the tests: the format of
OcTree::writeBinary (depth 16; per node two bytes, two bits per child:
00 unknown, 01 free leaf, 10 occupied leaf, 11 inner node; children 0-7 by
x bit + 2 * y bit + 4 * z bit of the key; inner children follow depth first).
Unpruned, which the reader accepts.
"""

from typing import Dict, Iterable, Tuple

Key = Tuple[int, int, int]
_DEPTH = 16
_ORIGIN = 32768  # OctoMap's key of the voxel at coordinate 0


def _write(node: Dict[Key, bool], level: int, out: bytearray) -> int:
    """Writes the node whose voxels (keys, occupied?) are `node`; level = bit
    of the key that picks the child. Returns the nodes written."""
    children = [dict() for _ in range(8)]
    for key, occupied in node.items():
        index = ((key[0] >> level) & 1) | (((key[1] >> level) & 1) << 1) | \
                (((key[2] >> level) & 1) << 2)
        children[index][key] = occupied
    bits = 0
    for i, child in enumerate(children):
        if not child:
            continue
        if level == 0:
            code = 0b10 if next(iter(child.values())) else 0b01
        else:
            code = 0b11
        bits |= code << (2 * i)
    out += bytes((bits & 0xFF, bits >> 8))
    count = 1
    if level > 0:
        for child in children:
            if child:
                count += _write(child, level - 1, out)
    else:
        count += sum(1 for child in children if child)
    return count


def write_bt(occupied: Iterable[Key], free: Iterable[Key] = (), resolution: float = 0.1) -> bytes:
    """A .bt of the voxels with integer keys (voxel i spans [i * res, (i + 1) * res))."""
    voxels: Dict[Key, bool] = {}
    for k in free:
        voxels[tuple(c + _ORIGIN for c in k)] = False
    for k in occupied:
        voxels[tuple(c + _ORIGIN for c in k)] = True
    body = bytearray()
    size = _write(voxels, _DEPTH - 1, body) if voxels else 0
    header = (f"# Octomap OcTree binary file\nid OcTree\nsize {size}\nres {resolution}\ndata\n")
    return header.encode() + bytes(body)


def room(size_x: int = 40, size_y: int = 30, height: int = 10,
         boxes: Iterable[Tuple[int, int, int, int, int]] = ()) -> Tuple[set, set]:
    """A room of size_x x size_y x height voxels with its corner at key 0:
    floor, four walls, boxes (x0, y0, x1, y1, h: solid) and free inside."""
    occupied, free = set(), set()
    for i in range(size_x):
        for j in range(size_y):
            for k in range(height):
                wall = i in (0, size_x - 1) or j in (0, size_y - 1)
                box = any(x0 <= i < x1 and y0 <= j < y1 and k < h for x0, y0, x1, y1, h in boxes)
                if k == 0 or wall or box:
                    occupied.add((i, j, k))
                elif k < height - 1:
                    free.add((i, j, k))
    return occupied, free
