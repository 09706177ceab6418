# FlightHelmet with its six meshes' primitives in one mesh under one node (every node has the identity
# transform, so nothing moves): the BVH a renderer builds over all static geometry at once.
import json, sys
src, dst = sys.argv[1], sys.argv[2]
g = json.load(open(src))
assert all(set(n) <= {"mesh", "name"} for n in g["nodes"]), "a node has a transform"
g["meshes"] = [{"name": "Merged", "primitives": [p for m in g["meshes"] for p in m["primitives"]]}]
g["nodes"] = [{"mesh": 0, "name": "Merged"}]
g["scenes"] = [{"nodes": [0]}]
g["scene"] = 0
json.dump(g, open(dst, "w"))
