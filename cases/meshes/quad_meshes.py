"""What the mesh scripts of this folder share (dodecahedron.py, pentagonal_prism.py,
pentagonal_antiprism.py): edge midpoints added once per edge, every face split into quads
around its centre, and the OBJ file they write (1-based, 17 digits)."""


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


def split_faces(vertices, faces):
    """Each face (corners counter-clockwise seen from outside) split into one quad per corner:
    (corner, midpoint of the next side, centre, midpoint of the previous side). Appends the
    midpoints and centres to `vertices`; returns the quads."""
    midpoint = Midpoints(vertices)
    quads = []
    for face in faces:
        centre = len(vertices)
        vertices.append(tuple(sum(vertices[c][d] for c in face) / len(face) for d in range(3)))
        m = len(face)
        for i in range(m):
            previous, corner, following = face[(i - 1) % m], face[i], face[(i + 1) % m]
            quads.append([corner, midpoint(corner, following), centre, midpoint(previous, corner)])
    return quads


def write_obj(path, header, vertices, quads):
    """`header`: comment lines (without '#'); quads: 0-based vertex indices."""
    with open(path, "w") as out:
        for line in header:
            out.write("# " + line + "\n")
        for v in vertices:
            out.write("v %.17g %.17g %.17g\n" % v)
        for q in quads:
            out.write("f %d %d %d %d\n" % tuple(i + 1 for i in q))
