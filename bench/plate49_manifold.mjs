// The 49-hole plate with Manifold (npm manifold-3d, WebAssembly), written as binary STL,
// as a peer for vproto's CSG. Usage: node plate49_manifold.mjs OUT.stl
import fs from 'node:fs';
import Module from 'manifold-3d';

const wasm = await Module();
wasm.setup();
const { Manifold } = wasm;

const holes = [];
for (let i = 0; i < 7; ++i)
  for (let j = 0; j < 7; ++j)
    holes.push(Manifold.cylinder(12, 4, 4, 64).translate([10 + 80 / 6 * i, 10 + 80 / 6 * j, -1]));
const plate = Manifold.cube([100, 100, 10]).subtract(Manifold.union(holes));
const mesh = plate.getMesh();

// binary STL: 80-byte header, count, then normal + 3 vertices + attribute per triangle
const tris = mesh.triVerts.length / 3;
const buf = Buffer.alloc(84 + 50 * tris);
buf.writeUInt32LE(tris, 80);
const p = (v, k) => mesh.vertProperties[v * mesh.numProp + k];
for (let t = 0; t < tris; ++t) {
  const o = 84 + 50 * t;
  for (let c = 0; c < 3; ++c)
    for (let k = 0; k < 3; ++k) buf.writeFloatLE(p(mesh.triVerts[3 * t + c], k), o + 12 + 12 * c + 4 * k);
}
fs.writeFileSync(process.argv[2], buf);
console.log(JSON.stringify({ volume_mm3: plate.volume(), triangles: tris }));
