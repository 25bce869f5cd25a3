//! Bad mesh files (issue 12 §1–3): every reader refuses malformed input with exit code 2
//! and a message naming the mesh file, the line (or byte), what is wrong, and the scene
//! that read it; counts in headers are checked against the file's size before anything
//! is allocated from them. One class of mistake per case; the files are written here.

mod common;

use common::bad::{BOX_ON_FLOOR, cli, expect, tmp};

const G22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const NODES: &str = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
const VTK: &str = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
const P4: &str = "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\n";

fn g22(elements: &str) -> String {
    format!("{G22}{NODES}$Elements\n{elements}$EndElements\n")
}

fn vtu(np: usize, points: &str, comps: usize, conn: &str, offsets: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <UnstructuredGrid>\n<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"1\">\n<Points>\n\
         <DataArray type=\"Float64\" NumberOfComponents=\"{comps}\" format=\"ascii\">{points}</DataArray>\n</Points>\n<Cells>\n\
         <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">{conn}</DataArray>\n\
         <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">{offsets}</DataArray>\n\
         <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">5</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"
    )
}

/// A Gmsh 2.2 binary file: the four nodes, then one element block as given.
fn g22_binary(block: &[i32]) -> Vec<u8> {
    let mut b = b"$MeshFormat\n2.2 1 8\n".to_vec();
    b.extend(1i32.to_le_bytes());
    b.extend(b"\n$EndMeshFormat\n$Nodes\n4\n");
    for (t, x) in [
        (1, [0.0, 0.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
        (3, [0.0, 1.0, 0.0]),
        (4, [0.0, 0.0, 1.0]),
    ] {
        b.extend(i32::to_le_bytes(t));
        for c in x {
            b.extend(f64::to_le_bytes(c));
        }
    }
    b.extend(b"\n$EndNodes\n$Elements\n1\n");
    for v in block {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"\n$EndElements\n");
    b
}

/// A Gmsh 4.1 tet with node tags `tags` (ASCII or binary).
fn g41_tet(tags: [u64; 4], binary: bool) -> Vec<u8> {
    let xyz = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    if !binary {
        let mut t =
            String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n");
        for g in tags {
            t += &format!("{g}\n");
        }
        for x in xyz {
            t += &format!("{} {} {}\n", x[0], x[1], x[2]);
        }
        t += "$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
        return t.into_bytes();
    }
    let mut b = b"$MeshFormat\n4.1 1 8\n".to_vec();
    b.extend(1i32.to_le_bytes());
    b.extend(b"\n$EndMeshFormat\n$Nodes\n");
    for v in [1u64, 4, 1, 4] {
        b.extend(v.to_le_bytes());
    }
    for v in [3i32, 1, 0] {
        b.extend(v.to_le_bytes());
    }
    b.extend(4u64.to_le_bytes());
    for g in tags {
        b.extend(g.to_le_bytes());
    }
    for x in xyz.iter().flatten() {
        b.extend(f64::to_le_bytes(*x));
    }
    b.extend(b"\n$EndNodes\n$Elements\n");
    for v in [1u64, 1, 1, 1] {
        b.extend(v.to_le_bytes());
    }
    for v in [3i32, 1, 4] {
        b.extend(v.to_le_bytes());
    }
    b.extend(1u64.to_le_bytes());
    for v in [1u64, 1, 2, 3, 4] {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"\n$EndElements\n");
    b
}

/// Issue 16 §6: Gmsh 4.1 files with a node tag defined twice were read (mshio keeps a
/// block's tags in a map, and drops them when their range looks dense); now refused in
/// ASCII and binary, while the same files with distinct tags read.
#[test]
fn duplicate_gmsh_41_node_tags_are_refused() {
    let dir = tmp("g41dup");
    for binary in [false, true] {
        std::fs::write(dir.join("ok.msh"), g41_tet([1, 2, 3, 4], binary)).unwrap();
        std::fs::write(dir.join("dup.msh"), g41_tet([1, 1, 3, 4], binary)).unwrap();
        for (mesh, bad) in [("ok.msh", false), ("dup.msh", true)] {
            let scene = BOX_ON_FLOOR.replace(
                "MESH",
                &format!("mesh = {{ generator = \"file\", path = \"{mesh}\" }}"),
            );
            std::fs::write(
                dir.join("s.toml"),
                scene.replace("nodes = \"z0\"", "nodes = \"all\""),
            )
            .unwrap();
            let r = cli(&dir, &["check", "s.toml"], &[]);
            if bad {
                expect(
                    &format!("duplicate 4.1 tag, binary {binary}"),
                    r,
                    2,
                    &["dup.msh", "node tag 1 is defined twice"],
                );
            } else {
                assert_eq!(r.0, 0, "binary {binary}: {}", r.1);
            }
        }
    }
}

#[test]
fn each_bad_mesh_is_refused_with_its_file_and_place() {
    let dir = tmp("meshes");
    let text = |s: &str| s.as_bytes().to_vec();
    let cases: Vec<(&str, &str, Vec<u8>, Vec<&str>)> = vec![
        (
            "duplicate Gmsh node tag",
            "dup.msh",
            text(&format!(
                "{G22}$Nodes\n4\n1 0 0 0\n1 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"
            )),
            vec!["node tag 1 is defined twice"],
        ),
        (
            "tag count past the line",
            "ntags.msh",
            text(&g22("1\n1 4 99 1 1 1 2 3 4\n")),
            vec!["line 13", "`1 4 99 1 1 1 2 3 4`"],
        ),
        (
            "negative node index",
            "neg.msh",
            text(&g22("1\n1 4 2 1 1 1 2 -3 4\n")),
            vec!["line 13", "non-negative integers"],
        ),
        (
            "undefined node tag",
            "undef.msh",
            text(&g22("1\n1 4 2 1 1 1 2 3 9\n")),
            vec!["node tag 9", "not defined"],
        ),
        (
            "section count mismatch",
            "count.msh",
            text(&format!(
                "{G22}$Nodes\n7\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"
            )),
            vec!["line 5", "count `7`", "4 lines"],
        ),
        (
            "unclosed section",
            "open.msh",
            text(&format!("{G22}{NODES}$Elements\n1\n1 4 2 1 1 1 2 3 4\n")),
            vec!["line 11", "not closed", "truncated"],
        ),
        (
            "too few element nodes",
            "few.msh",
            text(&g22("1\n1 4 2 1 1 1 2 3\n")),
            vec!["line 13", "lists 3 nodes", "has 4"],
        ),
        (
            "unsupported Gmsh version",
            "ver.msh",
            text("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n"),
            vec!["version 3.0", "4.1 and 2.2"],
        ),
        (
            "not a Gmsh file",
            "not.msh",
            text("hello\n"),
            vec!["no $MeshFormat"],
        ),
        (
            "inverted element",
            "inv.msh",
            text(&g22("1\n17 4 2 1 1 1 3 2 4\n")),
            vec![
                "inv.msh:element 17",
                "every corner: Jacobian determinant det J = -",
                "is inverted",
                "reorder the cell's nodes",
            ],
        ),
        (
            "degenerate element",
            "flat.msh",
            text(&format!(
                "{G22}$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n$EndNodes\n$Elements\n1\n5 4 2 1 1 1 2 3 4\n$EndElements\n"
            )),
            vec!["element 5", "degenerate"],
        ),
        (
            "non-finite coordinates",
            "nan.msh",
            text(&format!(
                "{G22}$Nodes\n4\n1 0 0 0\n2 nan 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"
            )),
            vec!["non-finite coordinates"],
        ),
        (
            "Gmsh 4.1 garbage",
            "bad41.msh",
            text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\nxx\n$EndNodes\n"),
            vec!["Gmsh 4.1 parse error"],
        ),
        (
            "binary 2.2 element count past the file",
            "bin_count.msh",
            g22_binary(&[4, 1_000_000_000, 2, 1, 1, 1, 1, 2, 3, 4]),
            vec!["$Elements block header", "bytes left"],
        ),
        (
            "binary 2.2 unknown element type",
            "bin_type.msh",
            g22_binary(&[77, 1, 0, 1, 1, 2, 3, 4]),
            vec!["element type 77"],
        ),
        (
            "binary 2.2 negative node",
            "bin_neg.msh",
            g22_binary(&[4, 1, 0, 1, 1, 2, -3, 4]),
            vec!["negative number"],
        ),
        (
            "absurd POINTS count",
            "big.vtk",
            text(&format!("{VTK}POINTS 2000000000 double\n0 0 0\n")),
            vec!["line 5", "6000000000", "bytes are left"],
        ),
        (
            "CELLS list past its end",
            "over.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 5\n9 0 1 2 3\nCELL_TYPES 1\n10\n"
            )),
            vec!["line 7", "runs past"],
        ),
        (
            "negative connectivity",
            "neg.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 5\n4 0 1 -2 3\nCELL_TYPES 1\n10\n"
            )),
            vec!["line 7", "-2 is not a valid index"],
        ),
        (
            "count whose product wraps",
            "wrap.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 6148914691236517206\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
            )),
            vec!["6148914691236517206", "bytes are left"],
        ),
        (
            "cells and types disagree",
            "types.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n"
            )),
            vec!["1 cells but 2 CELL_TYPES"],
        ),
        (
            "truncated ASCII data",
            "trunc.vtk",
            text(&format!("{VTK}{P4}CELLS 1 5\n4 0 1\n")),
            vec!["line 7", "truncated"],
        ),
        (
            "unknown section",
            "sec.vtk",
            text(&format!("{VTK}{P4}FOO 1\n")),
            vec!["line 7", "`FOO`"],
        ),
        (
            "node index past the points",
            "nodes.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 5\n4 0 1 2 7\nCELL_TYPES 1\n10\n"
            )),
            vec!["node 7", "defines 4 nodes"],
        ),
        (
            "unsupported cell type",
            "wedge.vtk",
            text(&format!(
                "{VTK}{P4}CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n13\n"
            )),
            vec!["VTK type 13", "tri3, quad4, tet4, hex8"],
        ),
        (
            "truncated binary data",
            "bin.vtk",
            text(
                "# vtk DataFile Version 4.2\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\nxx",
            ),
            vec!["truncated", "file ends at byte"],
        ),
        (
            "other dataset kind",
            "poly.vtk",
            text("# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\n"),
            vec!["UNSTRUCTURED_GRID", "POLYDATA"],
        ),
        (
            "not a legacy VTK file",
            "head.vtk",
            text("hello\n"),
            vec!["not a legacy VTK file"],
        ),
        (
            "2-component .vtu points",
            "pts2.vtu",
            text(&vtu(2, "0 0 1 0", 2, "0 1 0", "3")),
            vec![
                "line 6",
                "Points have 2 components",
                "NumberOfComponents=\"3\"",
            ],
        ),
        (
            "offsets past the connectivity",
            "offs.vtu",
            text(&vtu(3, "0 0 0 1 0 0 0 1 0", 3, "0 1 2", "9")),
            vec!["piece 0, cell 0", "offset 9 is outside [0, 3]"],
        ),
        (
            "not XML",
            "garbage.vtu",
            text("garbage"),
            vec!["no <VTKFile> element"],
        ),
        (
            "fewer point coordinates than NumberOfPoints says",
            "count.vtu",
            text(&vtu(4, "0 0 0 1 0 0 0 1 0", 3, "0 1 2", "3")),
            vec!["DataArray `", "9 values, expected 12"],
        ),
        (
            "a coordinate that is not a number",
            "nan.vtu",
            text(&vtu(3, "0 0 0 1 x 0 0 1 0", 3, "0 1 2", "3")),
            vec!["value 4 `x` is not a number"],
        ),
        (
            "a point index that is not an integer",
            "frac.vtu",
            text(&vtu(3, "0 0 0 1 0 0 0 1 0", 3, "0 1.5 2", "3")),
            vec!["piece 0, cell 0", "point index 1.5"],
        ),
        (
            "an unknown value type",
            "f16.vtu",
            text(&vtu(3, "0 0 0 1 0 0 0 1 0", 3, "0 1 2", "3").replace("Float64", "Float16")),
            vec!["type `Float16`", "Float32 or Float64"],
        ),
        (
            "an LZ4-compressed file",
            "lz4.vtu",
            text(&vtu(3, "0 0 0 1 0 0 0 1 0", 3, "0 1 2", "3").replace(
                "byte_order=",
                "compressor=\"vtkLZ4DataCompressor\" byte_order=",
            )),
            vec!["compressor `vtkLZ4DataCompressor` is not supported"],
        ),
        (
            "binary data that is not base64",
            "b64.vtu",
            text(&vtu(3, "@@@@", 3, "0 1 2", "3").replacen(
                "format=\"ascii\"",
                "format=\"binary\"",
                1,
            )),
            vec!["DataArray `", "base64 data"],
        ),
        (
            "a binary header that claims more bytes than present",
            "short.vtu",
            // UInt32 header 72 (9 f64), then only 8 bytes of data
            text(&vtu(3, "SAAAAAAAAAAAAAAA", 3, "0 1 2", "3").replacen(
                "format=\"ascii\"",
                "format=\"binary\"",
                1,
            )),
            vec!["header says 72 bytes, 8 present"],
        ),
        (
            "a zlib header that claims a bomb",
            "bomb.vtu",
            // 1 block of 2³¹ bytes from 4 compressed bytes
            text(
                &vtu(3, "AQAAAAAAAIAAAACABAAAAA==eJwDAA==", 3, "0 1 2", "3")
                    .replacen("format=\"ascii\"", "format=\"binary\"", 1)
                    .replace(
                        "byte_order=",
                        "compressor=\"vtkZLibDataCompressor\" byte_order=",
                    ),
            ),
            vec!["268435456 values: more than the 9 its piece can hold"],
        ),
        (
            "appended data without AppendedData",
            "app.vtu",
            text(&vtu(3, "", 3, "0 1 2", "3").replacen(
                "format=\"ascii\">",
                "format=\"appended\" offset=\"0\">",
                1,
            )),
            vec!["format=\"appended\" but the file has no AppendedData"],
        ),
    ];
    assert!(cases.len() >= 30);
    for (class, name, bytes, needles) in cases {
        std::fs::write(dir.join(name), &bytes).unwrap();
        let scene = BOX_ON_FLOOR
            .replace(
                "MESH",
                &format!("mesh = {{ generator = \"file\", path = \"{name}\" }}"),
            )
            .replace("nodes = \"z0\"", "nodes = \"boundary\"");
        std::fs::write(dir.join("scene.toml"), scene).unwrap();
        let mut want = vec![name, "scene.toml"];
        want.extend(needles);
        expect(class, cli(&dir, &["check", "scene.toml"], &[]), 2, &want);
    }
}
