#!/usr/bin/env python3
"""Writes assets/scenes/skinned_bar.gltf: a red bar standing in a white room open at the front,
skinned to two joints (`root` at its foot, `bend` 0.3 up it), under a spot light, seen by a
camera in front. The bar's vertices up to 0.2 follow `root`, from 0.4 up `bend`, the ring at 0.3
half each: turning `bend` bends the bar there. The skinned node `bar` has no transform, so at
the bind pose its vertices are where the mesh places them (as a reader that ignores skins sees
the file). One morph target, `flare`, widens the bar's top (its top ring and cap 0.05 further out
along x and z; its weight 0 in the file).

    python3 scripts/skinned-bar.py [OUT]
"""
import base64
import json
import math
import struct
import sys
from pathlib import Path

FOOT = (0.5, 0.0, 0.45)
HALF_WIDTH = 0.1
FLARE = 0.05
RINGS = [i / 10 for i in range(8)]  # 0 to 0.7
BEND_AT = 0.3


def bend_weight(y):
    return min(max((y - 0.2) / 0.2, 0.0), 1.0)


def room():
    """The floor, ceiling, back, left and right walls of the unit cube, facing in."""
    quads = [
        ([(0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 0, 0)], (0, 1, 0)),
        ([(0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)], (0, -1, 0)),
        ([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], (0, 0, 1)),
        ([(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)], (1, 0, 0)),
        ([(1, 0, 0), (1, 0, 1), (1, 1, 1), (1, 1, 0)], (-1, 0, 0)),
    ]
    positions, normals, indices = [], [], []
    for corners, normal in quads:
        base = len(positions)
        positions += corners
        normals += [normal] * 4
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return positions, normals, indices


def bar():
    """Four sides in rings up the bar, and its top; joints and weights a vertex."""
    x0, _, z0 = FOOT
    h = HALF_WIDTH
    # each side: its two bottom corners (counter-clockwise seen from outside) and its normal
    sides = [
        ((x0 - h, z0 + h), (x0 + h, z0 + h), (0, 0, 1)),
        ((x0 + h, z0 + h), (x0 + h, z0 - h), (1, 0, 0)),
        ((x0 + h, z0 - h), (x0 - h, z0 - h), (0, 0, -1)),
        ((x0 - h, z0 - h), (x0 - h, z0 + h), (-1, 0, 0)),
    ]
    positions, normals, weights, indices = [], [], [], []
    for a, b, normal in sides:
        base = len(positions)
        for y in RINGS:
            positions += [(a[0], y, a[1]), (b[0], y, b[1])]
            normals += [normal] * 2
            weights += [bend_weight(y)] * 2
        for ring in range(len(RINGS) - 1):
            i = base + 2 * ring
            indices += [i, i + 1, i + 3, i, i + 3, i + 2]
    base = len(positions)
    top = RINGS[-1]
    positions += [
        (x0 - h, top, z0 + h),
        (x0 + h, top, z0 + h),
        (x0 + h, top, z0 - h),
        (x0 - h, top, z0 - h),
    ]
    normals += [(0, 1, 0)] * 4
    weights += [1.0] * 4
    indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    joints = [(0, 1, 0, 0)] * len(positions)
    joint_weights = [(1.0 - w, w, 0.0, 0.0) for w in weights]
    # the morph target: the top's vertices moved out from the bar's axis
    flare = [
        (math.copysign(FLARE, p[0] - x0), 0.0, math.copysign(FLARE, p[2] - z0))
        if p[1] == top
        else (0.0, 0.0, 0.0)
        for p in positions
    ]
    return positions, normals, joints, joint_weights, indices, flare


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, rows, component, kind, target=None, bounds=False):
        offset = len(self.data)
        for row in rows:
            self.data += struct.pack("<" + fmt, *row)
        while len(self.data) % 4:
            self.data += b"\0"
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(self.data) - offset}
        if target:
            view["target"] = target
        self.views.append(view)
        accessor = {
            "bufferView": len(self.views) - 1,
            "componentType": component,
            "count": len(rows),
            "type": kind,
        }
        if bounds:
            accessor["min"] = [min(r[i] for r in rows) for i in range(3)]
            accessor["max"] = [max(r[i] for r in rows) for i in range(3)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "assets/scenes/skinned_bar.gltf")
    buffer = Buffer()
    vertices, indices = 34962, 34963
    p, n, i = room()
    room_primitive = {
        "attributes": {
            "POSITION": buffer.add("3f", p, 5126, "VEC3", vertices, True),
            "NORMAL": buffer.add("3f", n, 5126, "VEC3", vertices),
        },
        "indices": buffer.add("H", [(k,) for k in i], 5123, "SCALAR", indices),
        "material": 0,
    }
    p, n, j, w, i, flare = bar()
    bar_primitive = {
        "attributes": {
            "POSITION": buffer.add("3f", p, 5126, "VEC3", vertices, True),
            "NORMAL": buffer.add("3f", n, 5126, "VEC3", vertices),
            "JOINTS_0": buffer.add("4H", j, 5123, "VEC4", vertices),
            "WEIGHTS_0": buffer.add("4f", w, 5126, "VEC4", vertices),
        },
        "indices": buffer.add("H", [(k,) for k in i], 5123, "SCALAR", indices),
        "material": 1,
        "targets": [{"POSITION": buffer.add("3f", flare, 5126, "VEC3", vertices, True)}],
    }
    # column-major inverses of the joints' bind transforms (translations alone)
    def inverse_translation(t):
        return (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -t[0], -t[1], -t[2], 1)

    bend_place = (FOOT[0], FOOT[1] + BEND_AT, FOOT[2])
    inverse_binds = buffer.add(
        "16f", [inverse_translation(FOOT), inverse_translation(bend_place)], 5126, "MAT4"
    )
    # the spot at the front left, up high, aimed at the bar's middle
    spot_at, aim = (0.15, 0.95, 0.95), (0.5, 0.3, 0.45)
    forward = [a - b for a, b in zip(aim, spot_at)]
    length = math.sqrt(sum(c * c for c in forward))
    forward = [c / length for c in forward]
    # the rotation taking the node's -z to `forward`: about -z x forward
    axis = (forward[1], -forward[0], 0.0)
    sin = math.sqrt(sum(c * c for c in axis))
    angle = math.atan2(sin, -forward[2])
    s = math.sin(angle / 2) / sin
    rotation = [round(c * s, 9) for c in axis] + [round(math.cos(angle / 2), 9)]
    gltf = {
        "asset": {
            "version": "2.0",
            "generator": "written for quadray by scripts/skinned-bar.py: a red bar skinned to "
            "two joints (root, bend), with a morph target (flare), in a white room open at the "
            "front, under a spot light",
        },
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {
            "KHR_lights_punctual": {
                "lights": [
                    {
                        "name": "spot",
                        "type": "spot",
                        "color": [1.0, 1.0, 1.0],
                        "intensity": 1366.0,
                        "spot": {"innerConeAngle": 0.349065850, "outerConeAngle": 0.523598776},
                    }
                ]
            }
        },
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 4, 5]}],
        "nodes": [
            {"name": "room", "mesh": 0},
            {"name": "bar", "mesh": 1, "skin": 0},
            {"name": "root", "translation": list(FOOT), "children": [3]},
            {"name": "bend", "translation": [0.0, BEND_AT, 0.0]},
            {"name": "camera", "camera": 0, "translation": [0.5, 0.5, 2.0]},
            {
                "name": "spot light",
                "translation": list(spot_at),
                "rotation": rotation,
                "extensions": {"KHR_lights_punctual": {"light": 0}},
            },
        ],
        "skins": [{"name": "bar", "inverseBindMatrices": inverse_binds, "joints": [2, 3]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.872664626, "znear": 0.01}}],
        "meshes": [
            {"name": "room", "primitives": [room_primitive]},
            {
                "name": "bar",
                "primitives": [bar_primitive],
                "weights": [0.0],
                "extras": {"targetNames": ["flare"]},
            },
        ],
        "materials": [
            {
                "name": "white",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.73, 0.73, 0.73, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0,
                },
            },
            {
                "name": "red",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.8, 0.08, 0.06, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0,
                },
            },
        ],
        "accessors": buffer.accessors,
        "bufferViews": buffer.views,
        "buffers": [
            {
                "byteLength": len(buffer.data),
                "uri": "data:application/octet-stream;base64,"
                + base64.b64encode(bytes(buffer.data)).decode(),
            }
        ],
    }
    out.write_text(json.dumps(gltf, indent=1) + "\n")


main()
