"""Writes the .vtu variants of meshes/plate.vtu that tests/io_mesh_files.rs reads: every
DataArray format VTK and meshio write. Run from the repository root with a Python that
has vtk and meshio (pip install vtk meshio):  python tests/data/vtu/make.py"""
import meshio
import vtk

SRC = "meshes/plate.vtu"
OUT = "tests/data/vtu/"

m = meshio.read(SRC)
meshio.write(OUT + "plate_meshio_ascii.vtu", m, binary=False)
meshio.write(OUT + "plate_meshio_binary.vtu", m, compression=None)

r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(SRC)
r.Update()
grid = r.GetOutput()


def write(name, mode, encode=True, compress=True, uint64=False, big=False):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(OUT + name)
    w.SetInputData(grid)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[mode]()
    w.SetEncodeAppendedData(1 if encode else 0)
    if compress:
        w.SetCompressorTypeToZLib()
    else:
        w.SetCompressorTypeToNone()
    if uint64:
        w.SetHeaderTypeToUInt64()
    else:
        w.SetHeaderTypeToUInt32()
    if big:
        w.SetByteOrderToBigEndian()
    else:
        w.SetByteOrderToLittleEndian()
    assert w.Write() == 1, name


write("plate_vtk_appended_raw.vtu", "appended", encode=False, uint64=True)
write("plate_vtk_appended_raw_plain.vtu", "appended", encode=False, compress=False)
write("plate_vtk_appended_base64.vtu", "appended", encode=True)
write("plate_vtk_binary_big_endian.vtu", "binary", compress=False, big=True, uint64=True)
write("plate_vtk_ascii.vtu", "ascii")
