#!/usr/bin/env python3
"""Write the mesh of a binary PLY made by ../shared/bench/genmesh.py (x y z u v
floats; faces of a uchar count and three int indices) as a GLB with the same
vertices, texture coordinates and triangles (POSITION, TEXCOORD_0, u32
indices), for tools/gltf_load_bench.sh. Needs numpy.

Usage: ply_to_glb.py IN.ply OUT.glb"""
import json, struct, sys
import numpy as np

src, dst = sys.argv[1], sys.argv[2]
data = open(src, 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
header = data[:end].decode().split('\n')
nv = int(next(l for l in header if l.startswith('element vertex')).split()[2])
nf = int(next(l for l in header if l.startswith('element face')).split()[2])
verts = np.frombuffer(data, dtype=[('p', '<f4', (3,)), ('uv', '<f4', (2,))], count=nv, offset=end)
faces = np.frombuffer(data, dtype=[('n', 'u1'), ('i', '<i4', (3,))], count=nf, offset=end + nv * 20)
assert (faces['n'] == 3).all()
pos = np.ascontiguousarray(verts['p'])
uv = np.ascontiguousarray(verts['uv'])
ix = np.ascontiguousarray(faces['i'].astype('<u4'))
bin_ = pos.tobytes() + uv.tobytes() + ix.tobytes()
doc = {
    'asset': {'version': '2.0', 'generator': 'luster tools/ply_to_glb.py'},
    'scene': 0, 'scenes': [{'nodes': [0]}], 'nodes': [{'mesh': 0}],
    'meshes': [{'primitives': [{'attributes': {'POSITION': 0, 'TEXCOORD_0': 1}, 'indices': 2}]}],
    'buffers': [{'byteLength': len(bin_)}],
    'bufferViews': [
        {'buffer': 0, 'byteOffset': 0, 'byteLength': pos.nbytes, 'target': 34962},
        {'buffer': 0, 'byteOffset': pos.nbytes, 'byteLength': uv.nbytes, 'target': 34962},
        {'buffer': 0, 'byteOffset': pos.nbytes + uv.nbytes, 'byteLength': ix.nbytes, 'target': 34963},
    ],
    'accessors': [
        {'bufferView': 0, 'componentType': 5126, 'count': nv, 'type': 'VEC3',
         'min': pos.min(0).tolist(), 'max': pos.max(0).tolist()},
        {'bufferView': 1, 'componentType': 5126, 'count': nv, 'type': 'VEC2'},
        {'bufferView': 2, 'componentType': 5125, 'count': nf * 3, 'type': 'SCALAR'},
    ],
}
js = json.dumps(doc).encode()
js += b' ' * (-len(js) % 4)
bin_ += b'\0' * (-len(bin_) % 4)
with open(dst, 'wb') as f:
    f.write(b'glTF' + struct.pack('<II', 2, 12 + 8 + len(js) + 8 + len(bin_)))
    f.write(struct.pack('<I', len(js)) + b'JSON' + js)
    f.write(struct.pack('<I', len(bin_)) + b'BIN\0' + bin_)
print(f'{dst}: {nv} vertices, {nf} triangles')
