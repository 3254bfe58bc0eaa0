"""Render a knotwork .vtu with ParaView, as a user would see it.

    scripts/render_paraview.sh results/quarter_annulus/solution.vtu docs/quarter_annulus.png [field]

Opens the file with ParaView's own reader (so the Bezier cells, HigherOrderDegrees and
RationalWeights are interpreted by ParaView itself), colours by `field` (default
`solution`), shows the cell edges, and saves a PNG. Needs `scripts/install-deps.sh --paraview`; run it through render_paraview.sh.
"""
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, GetScalarBar,
                             ResetCamera, SaveScreenshot, Show, XMLUnstructuredGridReader)

source, png = sys.argv[1], sys.argv[2]
field = sys.argv[3] if len(sys.argv) > 3 else "solution"

reader = XMLUnstructuredGridReader(FileName=[source])
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1200, 900]
view.OrientationAxesVisibility = 0
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
display = Show(reader, view)
display.SetRepresentationType("Surface With Edges")
display.NonlinearSubdivisionLevel = 4  # draw the curved Bezier cells smoothly
display.EdgeColor = [0.2, 0.2, 0.2]
ColorBy(display, ("POINTS", field))
lut = GetColorTransferFunction(field)
lut.ApplyPreset("Viridis (matplotlib)", True)
display.SetScalarBarVisibility(view, True)
bar = GetScalarBar(lut, view)
bar.Title = field
bar.ComponentTitle = ""
bar.TitleColor = [0, 0, 0]
bar.LabelColor = [0, 0, 0]
bar.TitleFontSize = 20
bar.LabelFontSize = 18
view.CameraPosition = [0, 0, 10]
view.CameraViewUp = [0, 1, 0]
ResetCamera()
SaveScreenshot(png, view, ImageResolution=[1200, 900])
print("wrote", png)
