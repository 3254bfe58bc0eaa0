"""Render a knotwork .vtu with ParaView, as a user would see it.

    scripts/render_paraview.sh results/quarter_annulus/solution.vtu docs/quarter_annulus.png [field]
    scripts/render_paraview.sh results/lshape_adaptive/step_9.vtu docs/lshape_adaptive.png \
        error_indicator --cell-data --log --lines results/lshape_adaptive/step_9_knots.vtp

Opens the file with ParaView's own reader (so the Bezier cells, HigherOrderDegrees and
RationalWeights are interpreted by ParaView itself), colours by `field` (default
`solution`; --cell-data for a per-cell field such as the adaptive error indicator, --log
for a logarithmic colour scale), shows the cell edges (or, with --lines, the knot lines of
a .vtp written by `knotwork adapt`), and saves a PNG. Needs
`scripts/install-deps.sh --paraview`; run it through render_paraview.sh. --camera X,Y,Z
views a surface in R^3 from that direction (z up), e.g. the G1 surface of
`knotwork basis --g1 cases/meshes/cube.obj --vtk cube.vtu`.
"""
import argparse

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, GetScalarBar,
                             ResetCamera, SaveScreenshot, Show, XMLPolyDataReader, XMLUnstructuredGridReader)

parser = argparse.ArgumentParser()
parser.add_argument("source")
parser.add_argument("png")
parser.add_argument("field", nargs="?", default="solution")
parser.add_argument("--cell-data", action="store_true")
parser.add_argument("--log", action="store_true")
parser.add_argument("--lines")
parser.add_argument("--camera", help="x,y,z: look at the data from this direction (3D surfaces); default from +z")
parser.add_argument("--no-edges", action="store_true", help="hide the cell edges")
args = parser.parse_args()

reader = XMLUnstructuredGridReader(FileName=[args.source])
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1200, 900]
view.OrientationAxesVisibility = 0
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
display = Show(reader, view)
display.SetRepresentationType("Surface" if args.lines or args.no_edges else "Surface With Edges")
display.NonlinearSubdivisionLevel = 4  # draw the curved Bezier cells smoothly
display.EdgeColor = [0.2, 0.2, 0.2]
ColorBy(display, ("CELLS" if args.cell_data else "POINTS", args.field))
lut = GetColorTransferFunction(args.field)
lut.ApplyPreset("Viridis (matplotlib)", True)
if args.log:
    display.RescaleTransferFunctionToDataRange(False, True)
    lut.MapControlPointsToLogSpace()
    lut.UseLogScale = 1
display.SetScalarBarVisibility(view, True)
bar = GetScalarBar(lut, view)
bar.Title = args.field
bar.ComponentTitle = ""
bar.TitleColor = [0, 0, 0]
bar.LabelColor = [0, 0, 0]
bar.TitleFontSize = 20
bar.LabelFontSize = 18
if args.lines:
    lines = XMLPolyDataReader(FileName=[args.lines])
    shown = Show(lines, view)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = [0, 0, 0]
    shown.DiffuseColor = [0, 0, 0]
    shown.LineWidth = 1.5
if args.camera:
    view.CameraPosition = [float(c) for c in args.camera.split(",")]
    view.CameraFocalPoint = [0, 0, 0]
    view.CameraViewUp = [0, 0, 1]
else:
    view.CameraPosition = [0, 0, 10]
    view.CameraViewUp = [0, 1, 0]
ResetCamera()
SaveScreenshot(args.png, view, ImageResolution=[1200, 900])
print("wrote", args.png)
