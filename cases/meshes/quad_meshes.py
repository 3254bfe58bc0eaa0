"""What the mesh scripts of this folder share (dodecahedron.py, pentagonal_prism.py): edge
midpoints added once per edge, and the OBJ file they write (1-based, 17 digits)."""


class Midpoints:
    """The midpoint of each edge (a, b) of `vertices`, appended to it on first use."""

    def __init__(self, vertices):
        self.vertices = vertices
        self.index = {}

    def __call__(self, a, b):
        key = (min(a, b), max(a, b))
        if key not in self.index:
            self.index[key] = len(self.vertices)
            self.vertices.append(tuple((x + y) / 2 for x, y in zip(self.vertices[a], self.vertices[b])))
        return self.index[key]


def write_obj(path, header, vertices, quads):
    """`header`: comment lines (without '#'); quads: 0-based vertex indices."""
    with open(path, "w") as out:
        for line in header:
            out.write("# " + line + "\n")
        for v in vertices:
            out.write("v %.17g %.17g %.17g\n" % v)
        for q in quads:
            out.write("f %d %d %d %d\n" % tuple(i + 1 for i in q))
