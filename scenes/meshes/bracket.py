"""Writes bracket.msh (Gmsh 4.1 ASCII): an L-bracket surface, a horizontal flange
0.1 m x 0.05 m of 10 x 5 quads (z = 0) and a vertical flange 0.05 m x 0.05 m of
5 x 5 cells split into triangles (x = 0), sharing the edge x = 0, z = 0.
Run: python3 bracket.py > bracket.msh"""

nodes = {}  # (i, j, k) lattice of 10 mm -> tag


def node(i, j, k):
    return nodes.setdefault((i, j, k), len(nodes) + 1)


quads = [[node(i, j, 0), node(i + 1, j, 0), node(i + 1, j + 1, 0), node(i, j + 1, 0)]
         for j in range(5) for i in range(10)]
tris = []
for k in range(5):
    for j in range(5):
        a, b, c, d = node(0, j, k), node(0, j + 1, k), node(0, j + 1, k + 1), node(0, j, k + 1)
        tris += [[a, b, c], [a, c, d]]

out = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat", "$Nodes"]
n = len(nodes)
out.append(f"1 {n} 1 {n}")
out.append(f"2 1 0 {n}")
order = sorted(nodes.items(), key=lambda kv: kv[1])
out += [str(tag) for _, tag in order]
out += [f"{i * 0.01:g} {j * 0.01:g} {k * 0.01:g}" for (i, j, k), _ in order]
out.append("$EndNodes")
ne = len(quads) + len(tris)
out += ["$Elements", f"2 {ne} 1 {ne}", f"2 1 3 {len(quads)}"]
tag = 1
for q in quads:
    out.append(" ".join(map(str, [tag] + q)))
    tag += 1
out.append(f"2 2 2 {len(tris)}")
for t in tris:
    out.append(" ".join(map(str, [tag] + t)))
    tag += 1
out.append("$EndElements")
print("\n".join(out))
