#!/usr/bin/env python3
"""Renders a metrics.geometry error map (errors.vtp) with VTK, for the docs.

Two views side by side from one camera: the mesh colored by a distance array
(meters, a color bar) and by the `invented` flag. Not a test and not run in
CI; it needs python3-vtk9 and a display (xvfb-run on a headless machine):

  xvfb-run -a /usr/bin/python3 tools/error_map_screenshot.py OUT/errors.vtp \
      docs/images/error-map.png --eye 0 0 0.2 --target -0.64 -2.57 -1.0
"""
import argparse

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL backend)
import vtkmodules.vtkInteractionStyle  # noqa: F401
from vtkmodules.vtkCommonCore import vtkLookupTable
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow,
                                         vtkTextActor, vtkWindowToImageFilter)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("vtp")
    parser.add_argument("png")
    parser.add_argument("--array", default="distance_to_scan_m")
    parser.add_argument("--max", type=float, default=0.05, help="top of the color bar, meters")
    parser.add_argument("--eye", type=float, nargs=3, required=True)
    parser.add_argument("--target", type=float, nargs=3, required=True)
    parser.add_argument("--fov", type=float, default=60)
    parser.add_argument("--size", type=int, nargs=2, default=[1400, 640])
    parser.add_argument("--title", default="")
    args = parser.parse_args()

    reader = vtkXMLPolyDataReader()
    reader.SetFileName(args.vtp)
    reader.Update()
    poly = reader.GetOutput()
    point_data = poly.GetPointData()
    if point_data.GetArray(args.array) is None or point_data.GetArray("invented") is None:
        raise SystemExit(f"{args.vtp}: needs point arrays '{args.array}' and 'invented'")

    window = vtkRenderWindow()
    window.SetSize(*args.size)
    window.SetOffScreenRendering(1)

    distance_lut = vtkLookupTable()
    distance_lut.SetRange(0, args.max)
    distance_lut.SetHueRange(0.667, 0.0)  # blue (on the scan) to red (far)
    distance_lut.SetAboveRangeColor(0.5, 0.0, 0.0, 1.0)
    distance_lut.UseAboveRangeColorOn()
    distance_lut.Build()
    flag_lut = vtkLookupTable()
    flag_lut.SetNumberOfTableValues(2)
    flag_lut.SetRange(0, 1)
    flag_lut.SetTableValue(0, 0.78, 0.78, 0.78, 1.0)  # explained by the scan: gray
    flag_lut.SetTableValue(1, 0.85, 0.1, 0.1, 1.0)  # invented: red
    flag_lut.Build()

    panels = [(args.array, distance_lut, f"{args.array} (m)"), ("invented", flag_lut, "invented (red = 1)")]
    for index, (array, lut, label) in enumerate(panels):
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(poly)
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SetColorModeToMapScalars()  # `invented` is UInt8: map it, do not take it as a color
        mapper.SelectColorArray(array)
        mapper.SetLookupTable(lut)
        mapper.SetScalarRange(lut.GetRange())
        mapper.ScalarVisibilityOn()
        actor = vtkActor()
        actor.SetMapper(mapper)
        renderer = vtkRenderer()
        renderer.SetViewport(index / 2, 0, (index + 1) / 2, 1)
        renderer.SetBackground(1, 1, 1)
        renderer.AddActor(actor)
        camera = renderer.GetActiveCamera()
        camera.SetPosition(*args.eye)
        camera.SetFocalPoint(*args.target)
        camera.SetViewUp(0, 0, 1)
        camera.SetViewAngle(args.fov)
        renderer.ResetCameraClippingRange()
        text = vtkTextActor()
        text.SetInput(label if not args.title else f"{args.title}: {label}")
        text.GetTextProperty().SetColor(0, 0, 0)
        text.GetTextProperty().SetFontSize(20)
        text.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        text.GetPositionCoordinate().SetValue(0.02, 0.94)
        renderer.AddActor2D(text)
        if lut is distance_lut:
            bar = vtkScalarBarActor()
            bar.SetLookupTable(lut)
            bar.SetNumberOfLabels(6)
            bar.SetLabelFormat("%.3f")
            bar.GetLabelTextProperty().SetColor(0, 0, 0)
            bar.SetPosition(0.89, 0.1)
            bar.SetWidth(0.1)
            bar.SetHeight(0.8)
            renderer.AddActor2D(bar)
        window.AddRenderer(renderer)
    window.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtkPNGWriter()
    writer.SetFileName(args.png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


if __name__ == "__main__":
    main()
