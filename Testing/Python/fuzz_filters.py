# SPDX-License-Identifier: BSD-3-Clause
"""Seeded random malformed input through every filter of the plugin (pvpython).

    pvpython Testing/Python/fuzz_filters.py SEED COUNT

Each case takes the phantom's valid inputs, breaks one input of one filter at random (point ids
out of range or negative, NaN and infinite coordinates, empty blocks, points without cells, cells
of the wrong kind, point arrays of the wrong length or width, blocks that are not polydata,
duplicate block names, huge or tiny coordinates, a malformed OpenSim model or motion, a body mesh
file of random bytes, of counts it does not hold or of a cell beyond its points, a model nested deep
or of huge numbers, a body-transform table of NaN, scalings, reflections or missing columns, the
phantom's properties at their extremes) and runs the filter: each of the twelve proxies. A filter may refuse the input with a message or compute a result; it must not crash,
and a result must not hold non-finite coordinates. Before each case the script prints
"case K: <what>" so that a crash names the case; at the end it prints "fuzz: N cases, R refused,
A accepted". Exit code 0 when every case ended cleanly.
"""
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mdtesting  # noqa: E402
from paraview import simple  # noqa: E402
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkIdList, vtkStringArray  # noqa: E402
from vtkmodules.vtkCommonDataModel import (vtkCellArray, vtkImageData, vtkMultiBlockDataSet, vtkPolyData,  # noqa: E402
                                           vtkTable)

mdtesting.load_plugin()

SMALL_MODEL = """<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="knee">
 <Ground name="ground"/>
 <BodySet><objects><Body name="shank"/></objects></BodySet>
 <JointSet><objects>
  <CustomJoint name="knee"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/shank</socket_child_frame>
   <coordinates><Coordinate name="angle"><range>-2 2</range></Coordinate></coordinates>
   <SpatialTransform>
    <TransformAxis name="rotation1"><coordinates>angle</coordinates><axis>0 0 1</axis><LinearFunction name="function"><coefficients>1 0</coefficients></LinearFunction></TransformAxis>
    <TransformAxis name="translation1"><coordinates>angle</coordinates><axis>1 0 0</axis><SimmSpline name="function"><x>-2 0 1 2</x><y>0 0.1 0.2 0.1</y></SimmSpline></TransformAxis>
   </SpatialTransform></CustomJoint>
 </objects></JointSet>
""" + mdtesting.KNEE_MUSCLE
MOTION = "knee\nversion=1\ninDegrees=yes\nendheader\ntime angle\n0 0\n0.5 45\n1 90\n"
TETRAHEDRON = mdtesting.TETRAHEDRON


def copy_tree(tree):
    out = vtkMultiBlockDataSet()
    out.ShallowCopy(tree)
    return out


def leaves(tree):
    return [i for i in range(tree.GetNumberOfBlocks()) if isinstance(tree.GetBlock(i), vtkPolyData)]


def mutate_polydata(rng, data):
    """A broken deep copy of `data` and what was done to it."""
    out = vtkPolyData()
    out.DeepCopy(data)
    n = out.GetNumberOfPoints()
    kind = rng.choice(["id_far", "id_negative", "nan", "inf", "no_cells", "no_points", "lines_for_polys",
                       "polys_for_lines", "short_array", "wide_array", "huge", "tiny", "degenerate", "vertex_polys",
                       "duplicate_points", "collapse"])
    if kind in ("id_far", "id_negative"):
        bad = rng.choice([n, n + 1, 10 ** 9, 2 ** 31 - 1]) if kind == "id_far" else rng.choice([-1, -(10 ** 9)])
        ids = vtkIdList()
        for value in (0, min(1, max(n - 1, 0)), bad):
            ids.InsertNextId(value)
        # Into a copy of the cell array: a polydata without polygons shares VTK's one empty array.
        lines = out.GetNumberOfLines() and rng.random() < 0.5
        cells = vtkCellArray()
        cells.DeepCopy(out.GetLines() if lines else out.GetPolys())
        cells.InsertNextCell(ids)
        (out.SetLines if lines else out.SetPolys)(cells)
    elif kind in ("nan", "inf", "huge", "tiny") and n:
        value = {"nan": math.nan, "inf": math.inf, "huge": 1e300, "tiny": 1e-300}[kind]
        points = out.GetPoints()
        for _ in range(rng.randint(1, 3)):
            i = rng.randrange(n)
            p = list(points.GetPoint(i))
            p[rng.randrange(3)] = value if kind in ("nan", "inf") else p[0] * value
            points.SetPoint(i, p)
        if kind == "tiny":
            for i in range(n):
                points.SetPoint(i, [c * 1e-300 for c in points.GetPoint(i)])
    elif kind == "no_cells":
        out.SetPolys(vtkCellArray())
        out.SetLines(vtkCellArray())
    elif kind == "no_points":
        out = vtkPolyData()
    elif kind == "lines_for_polys":
        out.SetLines(out.GetPolys())
        out.SetPolys(vtkCellArray())
    elif kind == "polys_for_lines":
        out.SetPolys(out.GetLines())
        out.SetLines(vtkCellArray())
    elif kind in ("short_array", "wide_array"):
        array = vtkDoubleArray()
        array.SetName(rng.choice(["CurrentPosition", "Displacement", "Other"]))
        array.SetNumberOfComponents(3 if kind == "short_array" else 2)
        tuples = max(n - rng.randint(1, 3), 0) if kind == "short_array" else n
        array.SetNumberOfTuples(tuples)
        array.Fill(0.0)
        out.GetPointData().AddArray(array)
    elif kind == "degenerate" and out.GetNumberOfPolys():
        ids = vtkIdList()
        for value in (0, 0, 0):
            ids.InsertNextId(value)
        cells = vtkCellArray()
        cells.DeepCopy(out.GetPolys())
        cells.InsertNextCell(ids)
        out.SetPolys(cells)
    elif kind == "vertex_polys":
        cells = vtkCellArray()
        for i in range(min(n, 5)):
            cells.InsertNextCell(1)
            cells.InsertCellPoint(i)
        out.SetPolys(cells)
    elif kind == "duplicate_points" and n:
        points = out.GetPoints()
        for _ in range(10):
            points.SetPoint(rng.randrange(n), points.GetPoint(rng.randrange(n)))
    elif kind == "collapse" and n:
        points = out.GetPoints()
        for i in range(n):
            p = points.GetPoint(i)
            points.SetPoint(i, (p[0], p[1], 0.0))  # flat
    return out, kind


def mutate_tree(rng, tree):
    """A broken copy of a multiblock of polydata, and what was done."""
    out = copy_tree(tree)
    choice = rng.random()
    blocks = leaves(out)
    if choice < 0.1:
        out.SetBlock(rng.randrange(max(out.GetNumberOfBlocks(), 1)), None)
        return out, "empty block"
    if choice < 0.15:
        out.SetBlock(0, vtkImageData())
        return out, "image block"
    if choice < 0.2 and out.GetNumberOfBlocks() > 1:
        name = out.GetMetaData(0).Get(out.NAME())
        out.GetMetaData(1).Set(out.NAME(), name)
        return out, "duplicate block names"
    if choice < 0.25:
        return vtkMultiBlockDataSet(), "no blocks"
    index = rng.choice(blocks) if blocks else 0
    broken, kind = mutate_polydata(rng, out.GetBlock(index) or vtkPolyData())
    out.SetBlock(index, broken)
    return out, "block %d: %s" % (index, kind)


def producer(data):
    source = simple.PVTrivialProducer()
    source.GetClientSideObject().SetOutput(data)
    return source


class Inputs:
    """The phantom's valid data (small resolution, so that accepted cases run fast)."""

    def __init__(self):
        phantom = simple.MusculoskeletalPhantom(Resolution=8, Flexion=20)
        names = ["muscles", "bones_rest", "bones_current", "lines_rest", "lines_current"]
        self.data = {}
        for port, name in enumerate(names):
            phantom.UpdatePipeline()
            tree = vtkMultiBlockDataSet()
            tree.DeepCopy(phantom.GetClientSideObject().GetOutputDataObject(port))
            self.data[name] = tree
        matching = simple.ActionLineMatching(Input=producer(self.data["lines_rest"]),
                                             CurrentPose=producer(self.data["lines_current"]))
        matching.UpdatePipeline()
        self.data["matched"] = vtkMultiBlockDataSet()
        self.data["matched"].DeepCopy(matching.GetClientSideObject().GetOutputDataObject(0))
        self.data["transforms"] = body_transforms(self.data["bones_rest"])
        self.data["paths"] = muscle_paths(self.data["lines_rest"])


def muscle_paths(lines):
    """A block per polyline of `lines`, with a muscle's properties as the OpenSim reader writes
    them (lengths in mm), as MuscleFromPath takes them."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray
    tree = vtkMultiBlockDataSet()
    for b in range(lines.GetNumberOfBlocks()):
        leaf = lines.GetBlock(b)
        ids = leaf.GetLines()
        ids.InitTraversal()
        for cell in range(leaf.GetNumberOfLines()):
            path = vtkPolyData()
            points, line = vtkPoints(), vtkCellArray()
            cell_ids = leaf.GetCell(leaf.GetNumberOfVerts() + cell).GetPointIds()
            line.InsertNextCell(cell_ids.GetNumberOfIds())
            for k in range(cell_ids.GetNumberOfIds()):
                line.InsertCellPoint(points.InsertNextPoint(leaf.GetPoint(cell_ids.GetId(k))))
            path.SetPoints(points)
            path.SetLines(line)
            for name, value in (("max_isometric_force", 500.0), ("optimal_fiber_length", 40.0),
                                ("tendon_slack_length", 20.0), ("MetresPerLengthUnit", 0.001)):
                array = vtkDoubleArray()
                array.SetName(name)
                array.InsertNextValue(value)
                path.GetFieldData().AddArray(array)
            index = tree.GetNumberOfBlocks()
            tree.SetBlock(index, path)
            tree.GetMetaData(index).Set(vtkMultiBlockDataSet.NAME(), "path%d" % index)
    return tree


def body_transforms(bones):
    """A BodyTransforms table (as OpenSimModelReader writes it) naming each of `bones`' blocks,
    each a small rotation about z and a translation."""
    table = vtkTable()
    names = vtkStringArray()
    names.SetName("Body")
    table.AddColumn(names)
    columns = []
    for name in ["R%d%d" % (i, j) for i in range(3) for j in range(3)] + ["Tx", "Ty", "Tz"]:
        column = vtkDoubleArray()
        column.SetName(name)
        table.AddColumn(column)
        columns.append(column)
    c, s = math.cos(0.1), math.sin(0.1)
    for b in range(bones.GetNumberOfBlocks()):
        names.InsertNextValue(bones.GetMetaData(b).Get(vtkMultiBlockDataSet.NAME()))
        for column, value in zip(columns, (c, -s, 0, s, c, 0, 0, 0, 1, 1.0, 2.0, 3.0)):
            column.InsertNextValue(value)
    return table


def mutate_table(rng, table):
    """A broken copy of a BodyTransforms table, and what was done."""
    out = vtkTable()
    out.DeepCopy(table)
    kind = rng.choice(["nan", "inf", "scaled", "reflected", "huge", "no_column", "text_column", "no_rows",
                       "unknown_body"])
    row = rng.randrange(max(out.GetNumberOfRows(), 1))
    if kind in ("nan", "inf", "huge"):
        column = out.GetColumnByName(rng.choice(["R00", "R11", "R21", "Tx", "Tz"]))
        column.SetValue(row, {"nan": math.nan, "inf": -math.inf, "huge": 1e300}[kind])
    elif kind in ("scaled", "reflected"):
        for name in ("R00", "R01", "R02") if kind == "reflected" else ("R00", "R11", "R22"):
            column = out.GetColumnByName(name)
            column.SetValue(row, -column.GetValue(row) if kind == "reflected" else 2 * column.GetValue(row))
    elif kind == "no_column":
        out.RemoveColumnByName(rng.choice(["Body", "R12", "Ty"]))
    elif kind == "text_column":
        out.RemoveColumnByName("R00")
        text = vtkStringArray()
        text.SetName("R00")
        for _ in range(out.GetNumberOfRows()):
            text.InsertNextValue("x")
        out.AddColumn(text)
    elif kind == "no_rows":
        out = vtkTable()
        for c in range(table.GetNumberOfColumns()):
            empty = table.GetColumn(c).NewInstance()
            empty.SetName(table.GetColumn(c).GetName())
            out.AddColumn(empty)
    else:
        out.GetColumnByName("Body").SetValue(row, "nobody")
    return out, kind


# Each filter: its inputs as (property, data key, repeatable), and properties that keep it quick.
FILTERS = [
    ("ActionLineMatching", [("Input", "lines_rest", False), ("CurrentPose", "lines_current", False)], {}),
    ("BoneInterpolation", [("Input", "bones_rest", False), ("CurrentPose", "bones_current", False)], {}),
    ("HullDecimation", [("Input", "muscles", False)], {"TargetNumberOfPoints": 40}),
    ("MuscleDeformation", [("Input", "muscles", False), ("ActionLines", "matched", False),
                           ("Obstacles", "bones_current", True)],
     {"HullTargetNumberOfPoints": 40, "MaximumNumberOfIterations": 10}),
    ("IntersectionResolve", [("Input", "muscles", False), ("Obstacles", "bones_current", True)], {}),
    ("InterpolatedMuscleDeformation", [("Input", "muscles", False), ("BonesRest", "bones_rest", False),
                                       ("BonesCurrent", "bones_current", False),
                                       ("ActionLinesRest", "lines_rest", False),
                                       ("ActionLinesCurrent", "lines_current", False)],
     {"NumberOfSteps": 1, "HullTargetNumberOfPoints": 40, "MaximumNumberOfIterations": 10}),
    ("ActionLineGrouping", [("Input", "muscles", False), ("Paths", "lines_rest", False)], {}),
    ("MoveWithBodies", [("Input", "bones_rest", False), ("BodyTransforms", "transforms", False)], {}),
    ("PathsOverBones", [("Input", "lines_current", False), ("Bones", "bones_current", False)], {}),
    ("MuscleFromPath", [("Input", "paths", False), ("Bones", "bones_rest", False)], {"NumberOfPoints": 100}),
    # The bones and the lines of the motion: BoneInterpolation from the rest to the current pose.
    ("MotionMuscleDeformation", [("Input", "muscles", False), ("BonesRest", "bones_rest", False),
                                 ("BonesMotion", ("bones_rest", "bones_current"), False),
                                 ("ActionLinesRest", "lines_rest", False),
                                 ("ActionLinesMotion", ("lines_rest", "lines_current"), False)], {}),
]


def finite_output(proxy):
    """Every output's points finite, and every muscle's VolumeChangePercent that is given."""
    algorithm = proxy.GetClientSideObject()
    for port in range(algorithm.GetNumberOfOutputPorts()):
        data = algorithm.GetOutputDataObject(port)
        blocks = [data] if isinstance(data, vtkPolyData) else \
            [data.GetBlock(i) for i in range(data.GetNumberOfBlocks())] if isinstance(data, vtkMultiBlockDataSet) \
            else []
        for block in blocks:
            if not isinstance(block, vtkPolyData):
                continue
            if block.GetNumberOfPoints():
                values = block.GetPoints().GetData()
                for c in range(3):
                    low, high = values.GetRange(c)
                    if not (math.isfinite(low) and math.isfinite(high)):
                        return False
            change = block.GetFieldData().GetArray("VolumeChangePercent")
            if change is not None and not all(math.isfinite(change.GetValue(i))
                                              for i in range(change.GetNumberOfValues())):
                return False
    return True


def opensim_case(rng, folder):
    text, motion = SMALL_MODEL, MOTION
    kind = rng.choice(["truncate", "swap_tag", "bad_number", "bad_reference", "motion_truncate", "motion_nan",
                       "motion_column", "garbage", "mesh_bytes", "mesh_count", "mesh_id", "deep", "huge"])
    mesh = "shank.vtk"
    with open(os.path.join(folder, mesh), "w") as f:
        f.write(TETRAHEDRON)
    if kind == "truncate":
        text = text[:rng.randrange(len(text))]
    elif kind == "swap_tag":
        tag = rng.choice(["CustomJoint", "SimmSpline", "LinearFunction", "PathPoint", "Coordinate", "TransformAxis"])
        text = text.replace(tag, rng.choice(["Foo", "GCVSpline", "PinJoint", "Body"]), 2)
    elif kind == "bad_number":
        text = text.replace("0 1 0", rng.choice(["0 x 0", "nan 1 0", "0 1", "1e999 0 0"]), 1)
    elif kind == "bad_reference":
        text = text.replace(rng.choice(["/bodyset/shank", "/jointset/knee/angle", "/ground"]), "/nowhere", 1)
    elif kind == "motion_truncate":
        motion = motion[:rng.randrange(len(motion))]
    elif kind == "motion_nan":
        motion = motion.replace("45", rng.choice(["nan", "inf", "x", ""]))
    elif kind == "motion_column":
        motion = motion.replace("time angle", rng.choice(["angle time", "time elbow", "time", "time angle angle"]))
    elif kind == "mesh_bytes":
        mesh = rng.choice(["noise.stl", "noise.vtk", "noise.vtp", "noise.obj"])
        with open(os.path.join(folder, mesh), "wb") as f:
            f.write(bytes(rng.randrange(256) for _ in range(rng.choice([0, 10, 84, 600, 5000]))))
    elif kind == "mesh_count":
        mesh = "count.vtk"
        word = rng.choice(["POINTS 4", "POLYGONS 4 16"])
        with open(os.path.join(folder, mesh), "w") as f:
            f.write(TETRAHEDRON.replace(word, word.replace("4", str(rng.choice([0, 5, 2 ** 31 - 1, 10 ** 12])), 1)))
    elif kind == "mesh_id":
        mesh = "id.vtk"
        with open(os.path.join(folder, mesh), "w") as f:
            f.write(TETRAHEDRON.replace("3 1 2 3", "3 1 2 %d" % rng.choice([-1, 4, 10 ** 9])))
    elif kind == "deep":
        depth = rng.choice([300, 5000])
        text = text.replace('<Body name="shank"/>', '<Body name="shank">' + "<x>" * depth + "</x>" * depth + "</Body>")
    elif kind == "huge":
        text = text.replace("0 -1 0", rng.choice(["1e300 -1 0", "0 -1e12 0", "1e13 0 0"]), 1)
        motion = motion.replace("45", rng.choice(["1e307", "1e12", "45"]))
    else:
        text = "".join(chr(rng.randrange(32, 127)) for _ in range(200))
    text = text.replace('<Body name="shank"/>', '<Body name="shank"><attached_geometry><Mesh name="m"><mesh_file>%s'
                        '</mesh_file></Mesh></attached_geometry></Body>' % mesh)
    model = os.path.join(folder, "fuzz.osim")
    with open(model, "w") as f:
        f.write(text)
    with open(os.path.join(folder, "fuzz.mot"), "w") as f:
        f.write(motion)
    reader = simple.OpenSimModelReader(FileName=model, MotionFileName=os.path.join(folder, "fuzz.mot"))
    return reader, "OpenSimModelReader: " + kind


def main():
    seed, count = int(sys.argv[1]), int(sys.argv[2])
    rng = random.Random(seed)
    inputs = Inputs()
    folder = mdtesting.output_dir("fuzz")
    refused = accepted = 0
    # FUZZ_CASES=K[,K...] runs only those cases (the others are drawn, not run): to replay a
    # crash, alone or after the cases that led to it.
    chosen = {int(k) for k in os.environ.get("FUZZ_CASES", "").split(",") if k}
    for case in range(count):
        run = not chosen or case in chosen
        draw = rng.random()
        if draw < 0.03:
            settings = {"Resolution": rng.choice([1, 2, 3, 8, 64]), "Flexion": rng.uniform(-400, 400)}
            print("case %d: MusculoskeletalPhantom %s" % (case, settings), flush=True)
            with mdtesting.CapturedMessages() as messages:
                proxy = simple.MusculoskeletalPhantom(**settings)
                if run:
                    proxy.UpdatePipeline()
            if run and not finite_output(proxy):
                print("case %d: MusculoskeletalPhantom put out non-finite coordinates" % case, flush=True)
                return 1
        elif draw < 0.15:
            with mdtesting.CapturedMessages() as messages:
                proxy, what = opensim_case(rng, folder)
                print("case %d: %s" % (case, what), flush=True)
                if run:
                    proxy.UpdatePipeline()
            if run and not finite_output(proxy):
                print("case %d: OpenSimModelReader put out non-finite coordinates" % case, flush=True)
                return 1
        else:
            name, ports, settings = rng.choice(FILTERS)
            broken = rng.randrange(len(ports))
            sources, what = {}, None
            for index, (prop, key, repeatable) in enumerate(ports):
                keys = key if isinstance(key, tuple) else (key,)
                datas = [inputs.data[k] for k in keys]
                if index == broken:
                    which = rng.randrange(len(datas))
                    mutate = mutate_table if isinstance(datas[which], vtkTable) else mutate_tree
                    datas[which], what = mutate(rng, datas[which])
                if len(datas) == 2:
                    source = simple.BoneInterpolation(Input=producer(datas[0]), CurrentPose=producer(datas[1]),
                                                      NumberOfSteps=2)
                else:
                    source = producer(datas[0])
                sources[prop] = [source] if repeatable else source
            print("case %d: %s.%s %s" % (case, name, ports[broken][0], what), flush=True)
            with mdtesting.CapturedMessages() as messages:
                proxy = getattr(simple, name)(**sources, **settings)
                if run:
                    proxy.UpdatePipeline()
            if not finite_output(proxy):
                print("case %d: %s put out non-finite coordinates" % (case, name), flush=True)
                return 1
        if not run:
            pass
        elif "ERR" in messages.text or "Error" in messages.text:
            refused += 1
        else:
            accepted += 1
        # Consumers before their producers.
        for source in reversed(list(simple.GetSources().values())):
            simple.Delete(source)
    print("fuzz: %d cases, %d refused, %d accepted" % (refused + accepted, refused, accepted), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
