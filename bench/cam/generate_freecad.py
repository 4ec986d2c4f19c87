# Writes four of bench/cam's programs with FreeCAD's Path workbench (CAM), headless:
#   freecadcmd bench/cam/generate_freecad.py     (from the repository root; FreeCAD 0.20, Debian's freecad-python3)
# Each model is built here with Part scripting, its top at Z=0 and its stock the model's bounding box, so that
# the stock given to frepmill simulate is the box named in each program's header. The programs are posted with
# FreeCAD's linuxcnc post-processor; the header names the CAM system, its version, the operation and the stock.
import os

import FreeCAD
import Part
from FreeCAD import Vector

from PathScripts import PathJob, PathToolBit, PathToolController
from PathScripts import PathPocketShape, PathAdaptive, PathProfile, PathHelix, PathDrilling, PathVcarve
from PathScripts.post import linuxcnc_post
from PathScripts import PathUtils

# With more than one tool controller in a job, FreeCAD asks in a dialog which one a new operation takes; headless
# there is no dialog (PathUtils.findToolController fails), so the first is taken and each operation sets its own.
_find_tool_controller = PathUtils.findToolController
PathUtils.findToolController = lambda obj, proxy, name=None: (
    PathUtils.getToolControllers(obj, proxy)[0] if len(PathUtils.getToolControllers(obj, proxy)) > 1
    else _find_tool_controller(obj, proxy, name))

OUT = os.environ.get("FM_CAM_OUT", os.path.join(os.getcwd(), "bench", "cam"))
FONT = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"
SHAPES = FreeCAD.getHomePath() + "Mod/Path/Tools/Shape/"


def new_doc(name):
    return FreeCAD.newDocument(name)


def make_job(doc, part_shape, name):
    part = doc.addObject("Part::Feature", name)
    part.Shape = part_shape
    doc.recompute()
    job = PathJob.Create("Job", [part], None)
    stock = job.Stock
    for ext in ("ExtXneg", "ExtXpos", "ExtYneg", "ExtYpos", "ExtZneg", "ExtZpos"):
        if hasattr(stock, ext):
            getattr(stock, ext).Value = 0.0
    job.GeometryTolerance.Value = 0.01
    # drop the default tool controller: each program adds its own
    for tc in list(job.Tools.Group):
        job.Tools.removeObject(tc)
    doc.recompute()
    return job, job.Model.Group[0]


def tool(doc, job, number, label, shape, params, hfeed, vfeed, rpm):
    bit = PathToolBit.Factory.Create("Bit%d" % number, SHAPES + shape)
    bit.Label = label
    for key, value in params.items():
        setattr(bit, key, value)
    tc = PathToolController.Create("TC%d" % number, bit, number)
    tc.Label = "TC: " + label
    tc.HorizFeed = FreeCAD.Units.Quantity("%g mm/min" % hfeed)
    tc.VertFeed = FreeCAD.Units.Quantity("%g mm/min" % vfeed)
    tc.HorizRapid = 0
    tc.SpindleSpeed = rpm
    job.Proxy.addToolController(tc)
    return tc


def faces_at(model, z, normal_up=True):
    names = []
    for i, f in enumerate(model.Shape.Faces):
        bb = f.BoundBox
        if abs(bb.ZMin - z) < 1e-6 and abs(bb.ZMax - z) < 1e-6:
            names.append("Face%d" % (i + 1))
    return names


def post(doc, job, path, header):
    doc.recompute()
    objs = []
    current_tc = None
    for o in job.Operations.Group:
        if len(o.Path.Commands) == 0:
            raise SystemExit("%s: operation %s made no path" % (path, o.Label))
        if o.ToolController != current_tc:  # as FreeCAD's PathPost does: the tool change before the operation
            current_tc = o.ToolController
            objs.append(current_tc)
        objs.append(o)
    tmp = path + ".tmp"
    linuxcnc_post.export(objs, tmp, "--no-show-editor --precision 3")
    ver = FreeCAD.Version()
    with open(tmp) as f:
        body = f.read()
    os.remove(tmp)
    with open(path, "w") as f:
        f.write("(Written by FreeCAD %s.%s.%s Path workbench, linuxcnc_post; bench/cam/generate_freecad.py)\n"
                % (ver[0], ver[1], ver[2]))
        for line in header:  # G-code comments do not nest: no parentheses inside
            f.write("(%s)\n" % line.replace("(", "[").replace(")", "]"))
        f.write(body)
    print("%s: %d lines" % (path, body.count("\n")))


def box(x0, y0, z0, x1, y1, z1):
    return Part.makeBox(x1 - x0, y1 - y0, z1 - z0, Vector(x0, y0, z0))


def rounded_box(x0, y0, z0, x1, y1, z1, radius):
    """A box whose vertical edges are filleted."""
    solid = box(x0, y0, z0, x1, y1, z1)
    return solid.makeFillet(radius, [e for e in solid.Edges if abs(e.BoundBox.XLength) < 1e-6
                                     and abs(e.BoundBox.YLength) < 1e-6])


def pocket_raster():
    """A 58x50 mm pocket 3.2 mm deep, cleared by ZigZag passes along X 0.16 mm apart with a 1 mm flat."""
    doc = new_doc("pocket_raster")
    shape = box(0, 0, -10, 70, 62, 0).cut(box(6, 6, -3.4, 64, 56, 1))
    job, model = make_job(doc, shape, "Plate")
    tc = tool(doc, job, 1, "1 mm flat end mill", "endmill.fcstd",
              {"Diameter": 1.0, "CuttingEdgeHeight": 4.0, "Length": 20.0, "ShankDiameter": 3.0}, 600, 100, 18000)
    op = PathPocketShape.Create("PocketRaster", None, job)
    op.Base = [(model, faces_at(model, -3.4))]
    op.ToolController = tc
    op.OffsetPattern = "ZigZag"
    op.ZigZagAngle = 0
    op.StepOver = 16
    op.setExpression("StepDown", None)
    op.StepDown.Value = 0.2
    op.MinTravel = False
    doc.recompute()
    post(doc, job, os.path.join(OUT, "freecad_pocket_raster.ngc"),
         ["operation: Pocket Shape, ZigZag at 0 deg, step-over 16% (0.16 mm), step-down 0.2 mm, to Z-3.4",
          "pocket 58 x 50 mm (X6..64 Y6..56); tool T1: 1 mm flat end mill",
          "stock: box:0,0,-10,70,62,0"])


def adaptive_pocket():
    """A rounded 70x50 mm pocket 6 mm deep around a 20 mm round island, cleared adaptively with a 4 mm flat."""
    doc = new_doc("adaptive_pocket")
    cavity = rounded_box(10, 10, -6, 80, 60, 1, 8.0)
    island = Part.makeCylinder(10, 8, Vector(45, 35, -7))
    shape = box(0, 0, -15, 90, 70, 0).cut(cavity.cut(island))
    job, model = make_job(doc, shape, "Plate")
    tc = tool(doc, job, 2, "4 mm flat end mill", "endmill.fcstd",
              {"Diameter": 4.0, "CuttingEdgeHeight": 12.0, "Length": 40.0, "ShankDiameter": 4.0}, 1200, 300, 16000)
    op = PathAdaptive.Create("Adaptive", None, job)
    op.Base = [(model, faces_at(model, -6.0))]
    op.ToolController = tc
    op.Side = "Inside"
    op.OperationType = "Clearing"
    op.StepOver = 15
    op.setExpression("StepDown", None)
    op.StepDown.Value = 3.0
    op.HelixAngle = 5
    op.HelixDiameterLimit.Value = 0
    op.LiftDistance.Value = 0.5
    op.FinishingProfile = True
    op.Tolerance = 0.05
    doc.recompute()
    post(doc, job, os.path.join(OUT, "freecad_adaptive.ngc"),
         ["operation: Adaptive clearing, step-over 15%, step-down 3 mm, helix entry 5 deg, finishing profile, to Z-6",
          "pocket 70 x 50 mm with 8 mm corners round a 20 mm island at X45 Y35; tool T2: 4 mm flat end mill",
          "stock: box:0,0,-15,90,70,0"])


def plate_outline():
    """A rounded plate cut out of its stock (Profile), a 20 mm bore (Helix) and four 5 mm holes (Drilling, G83)."""
    doc = new_doc("plate_outline")
    plate = rounded_box(5, 5, -10, 95, 55, 0, 10.0)
    plate = plate.cut(Part.makeCylinder(10, 12, Vector(50, 30, -11)))
    for x, y in ((17, 17), (83, 17), (17, 43), (83, 43)):
        plate = plate.cut(Part.makeCylinder(2.5, 12, Vector(x, y, -11)))
    job, model = make_job(doc, plate, "Plate")
    for ext in ("ExtXneg", "ExtXpos", "ExtYneg", "ExtYpos"):
        getattr(job.Stock, ext).Value = 5.0
    doc.recompute()
    drill = tool(doc, job, 3, "5 mm drill", "drill.fcstd",
                 {"Diameter": 5.0, "TipAngle": 118.0, "Length": 50.0}, 200, 200, 3000)
    mill = tool(doc, job, 4, "6 mm flat end mill", "endmill.fcstd",
                {"Diameter": 6.0, "CuttingEdgeHeight": 20.0, "Length": 50.0, "ShankDiameter": 6.0}, 900, 200, 12000)
    holes = []
    bore = []
    for i, f in enumerate(model.Shape.Faces):
        if isinstance(f.Surface, Part.Cylinder):
            if abs(f.Surface.Radius - 2.5) < 1e-6:
                holes.append("Face%d" % (i + 1))
            elif abs(f.Surface.Radius - 10.0) < 1e-6 and abs(f.Surface.Center.x - 50) < 1e-6:  # not a corner
                bore.append("Face%d" % (i + 1))
    # Create() would look for every hole of the model before the job has set it (fails headless): the bases are
    # given here instead
    dr = doc.addObject("Path::FeaturePython", "Drilling")
    dr.Proxy = PathDrilling.ObjectDrilling(dr, "Drilling", job)
    dr.Base = [(model, holes)]
    dr.ToolController = drill
    dr.PeckEnabled = True
    dr.setExpression("PeckDepth", None)
    dr.PeckDepth.Value = 2.5
    dr.setExpression("FinalDepth", None)
    dr.FinalDepth.Value = -10.0
    he = doc.addObject("Path::FeaturePython", "Helix")
    he.Proxy = PathHelix.ObjectHelix(he, "Helix", job)
    he.Base = [(model, bore)]
    he.ToolController = mill
    he.StepOver = 50
    he.setExpression("FinalDepth", None)
    he.FinalDepth.Value = -10.0
    pr = PathProfile.Create("Profile", None, job)
    pr.ToolController = mill
    pr.Side = "Outside"
    pr.processPerimeter = True
    pr.processHoles = False
    pr.processCircles = False
    pr.setExpression("StepDown", None)
    pr.StepDown.Value = 2.5
    pr.setExpression("FinalDepth", None)
    pr.FinalDepth.Value = -10.0
    doc.recompute()
    post(doc, job, os.path.join(OUT, "freecad_plate_outline.ngc"),
         ["operations: Drilling (G83, peck 2.5 mm) of four 5 mm holes; Helix 20 mm bore at X50 Y30;",
          "Profile outside the 90 x 50 mm plate with 10 mm corners (X5..95 Y5..55), step-down 2.5 mm; all to Z-10",
          "tools: T3 5 mm drill (118 deg), T4 6 mm flat end mill",
          "stock: box:0,0,-10,100,60,0"])


def engraving():
    """The word 'frepmill' (DejaVu Sans Bold, 14 mm) V-carved with a 60 degree V-bit into a plate."""
    doc = new_doc("engraving")
    import Draft
    text = Draft.make_shapestring("frepmill", FONT, 14.0, 0.0)
    text.Placement.Base = Vector(6, 8, 0)
    doc.recompute()
    job, model = make_job(doc, box(0, 0, -8, 110, 36, 0), "Plate")
    vbit = tool(doc, job, 5, "60 deg V-bit", "v-bit.fcstd",
                {"Diameter": 6.0, "CuttingEdgeAngle": 60.0, "TipDiameter": 0.2, "CuttingEdgeHeight": 6.0,
                 "Length": 30.0, "ShankDiameter": 6.0}, 600, 200, 18000)
    op = PathVcarve.Create("Vcarve", None, job)
    op.BaseShapes = [text] if hasattr(op, "BaseShapes") else []
    op.Base = [(text, ["Face%d" % (i + 1) for i in range(len(text.Shape.Faces))])]
    op.ToolController = vbit
    op.setExpression("FinalDepth", None)
    op.FinalDepth.Value = -3.0
    op.setExpression("StartDepth", None)
    op.StartDepth.Value = 0.0
    doc.recompute()
    post(doc, job, os.path.join(OUT, "freecad_vcarve_text.ngc"),
         ["operation: V-carve of the text 'frepmill' (DejaVu Sans Bold, 14 mm high, from X6 Y8), depth from",
          "the medial axis (varying Z), at most 3 mm; tool T5: 60 deg V-bit, 6 mm, 0.2 mm tip",
          "stock: box:0,0,-8,110,36,0"])


# freecadcmd runs this file as a macro (its __name__ is not "__main__"): everything, or the one program that
# FM_CAM_ONLY names
which = os.environ.get("FM_CAM_ONLY", "")
for fn in (pocket_raster, adaptive_pocket, plate_outline, engraving):
    if not which or which == fn.__name__:
        fn()
