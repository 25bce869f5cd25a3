//! VTU encoding: the XML of a frame with its arrays zlib-compressed and base64-encoded
//! from reused buffers, the arrays that never change encoded once.

use super::*;

impl FrameWriter {
    pub(super) fn encode(&mut self, time: f64, step: usize) {
        let g = &self.geom;
        let (np, nc) = (g.points.len(), g.cells.len());
        let compressed = self.encoding == Encoding::Zlib;
        let mut x = std::mem::take(&mut self.xml);
        x.clear();
        let _ = write!(
            x,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\"{}>\n<UnstructuredGrid>\n",
            if compressed {
                " compressor=\"vtkZLibDataCompressor\""
            } else {
                ""
            }
        );
        x.push_str("<FieldData>\n");
        self.array_f64(&mut x, "TimeValue", 1, &[time]);
        self.array_i64(&mut x, "Step", 1, &[step as i64]);
        x.push_str("</FieldData>\n");
        let _ = writeln!(x, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">");
        x.push_str("<PointData Vectors=\"displacement\" Scalars=\"gap\">\n");
        let (disp, vel, force, gap) = (
            std::mem::take(&mut self.disp),
            std::mem::take(&mut self.vel),
            std::mem::take(&mut self.force),
            std::mem::take(&mut self.gap),
        );
        self.array_f64(&mut x, "displacement", 3, &disp);
        self.array_f64(&mut x, "velocity", 3, &vel);
        self.array_f64(&mut x, "contact_force", 3, &force);
        self.array_f64(&mut x, "gap", 1, &gap);
        (self.disp, self.vel, self.force, self.gap) = (disp, vel, force, gap);
        if !self.status.is_empty() {
            let status = std::mem::take(&mut self.status);
            self.array_f64(&mut x, "contact_status", 1, &status);
            self.status = status;
        }
        x.push_str(&self.static_point_xml);
        let [(strain_name, _), (stress_name, _), _] = self.cell_arrays();
        let _ = write!(
            x,
            "</PointData>\n<CellData Tensors=\"{stress_name}\" Scalars=\"von_mises\">\n"
        );
        let (strain, stress, mises) = (
            std::mem::take(&mut self.strain),
            std::mem::take(&mut self.stress),
            std::mem::take(&mut self.mises),
        );
        self.array_f64(&mut x, strain_name, 6, &strain);
        self.array_f64(&mut x, stress_name, 6, &stress);
        self.array_f64(&mut x, "von_mises", 1, &mises);
        (self.strain, self.stress, self.mises) = (strain, stress, mises);
        x.push_str("</CellData>\n");
        x.push_str(&self.static_xml);
        x.push_str("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        self.xml = x;
    }

    /// The `<Points>` and `<Cells>` elements, encoded once for every frame.
    pub(super) fn encode_static(&mut self) -> String {
        let mut x = String::from("<Points>\n");
        let pts: Vec<f64> = self.geom.points.iter().flatten().copied().collect();
        self.array_f64(&mut x, "Points", 3, &pts);
        x.push_str("</Points>\n<Cells>\n");
        let conn: Vec<i64> = self
            .geom
            .cells
            .iter()
            .flat_map(|(_, n, _)| n.iter().map(|&v| v as i64))
            .collect();
        let offs: Vec<i64> = self
            .geom
            .cells
            .iter()
            .scan(0i64, |o, (_, n, _)| {
                *o += n.len() as i64;
                Some(*o)
            })
            .collect();
        let types: Vec<u8> = self
            .geom
            .cells
            .iter()
            .map(|(k, _, _)| vtk_type(k))
            .collect();
        self.array_i64(&mut x, "connectivity", 1, &conn);
        self.array_i64(&mut x, "offsets", 1, &offs);
        self.array_raw(&mut x, "UInt8", "types", 1, types.len(), &types, |s, v| {
            for b in v {
                let _ = write!(s, "{b} ");
            }
        });
        x.push_str("</Cells>\n");
        x
    }

    pub(super) fn array_f64(&mut self, x: &mut String, name: &str, comps: usize, v: &[f64]) {
        let bytes: &[u8] = bytemuck_f64(v);
        self.array_raw(x, "Float64", name, comps, v.len(), bytes, |s, _| {
            for (k, a) in v.iter().enumerate() {
                let _ = write!(s, "{a:e}");
                s.push(if (k + 1) % comps == 0 { '\n' } else { ' ' });
            }
        });
    }

    pub(super) fn array_i64(&mut self, x: &mut String, name: &str, comps: usize, v: &[i64]) {
        let bytes: Vec<u8> = v.iter().flat_map(|a| a.to_le_bytes()).collect();
        self.array_raw(x, "Int64", name, comps, v.len(), &bytes, |s, _| {
            for a in v {
                let _ = write!(s, "{a} ");
            }
        });
    }

    /// One `<DataArray>`; `ascii` prints the values for the ASCII encoding.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn array_raw(
        &mut self,
        x: &mut String,
        ty: &str,
        name: &str,
        comps: usize,
        len: usize,
        bytes: &[u8],
        ascii: impl Fn(&mut String, &[u8]),
    ) {
        let fmt = if self.encoding == Encoding::Ascii {
            "ascii"
        } else {
            "binary"
        };
        let unit = match name {
            "displacement" | "gap" | "Points" => " units=\"m\"",
            "velocity" => " units=\"m/s\"",
            "contact_force" => " units=\"N\"",
            "stress" | "cauchy_stress" | "von_mises" => " units=\"Pa\"",
            "strain" | "green_lagrange_strain" => " units=\"1\"",
            "TimeValue" => " units=\"s\"",
            _ => "",
        };
        let _ = writeln!(
            x,
            "<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" \
             NumberOfTuples=\"{}\" format=\"{fmt}\"{unit}>",
            len / comps.max(1)
        );
        match self.encoding {
            Encoding::Ascii => ascii(x, bytes),
            Encoding::Binary => {
                self.raw.clear();
                self.raw
                    .extend_from_slice(&(bytes.len() as u64).to_le_bytes());
                self.raw.extend_from_slice(bytes);
                B64.encode_string(&self.raw, x);
            }
            Encoding::Zlib => {
                // one block: header [nblocks, block size, last block size, compressed
                // size], base64-encoded on its own, then the compressed block
                self.zip.clear();
                if !bytes.is_empty() {
                    // one reused deflate state (a fresh one zeroes its window each time)
                    self.deflate.reset();
                    self.zip.reserve(bytes.len() / 2 + 64);
                    loop {
                        let done = self.deflate.total_in() as usize;
                        let st = self
                            .deflate
                            .compress_vec(
                                &bytes[done..],
                                &mut self.zip,
                                flate2::FlushCompress::Finish,
                            )
                            .expect("deflate into memory");
                        if st == flate2::Status::StreamEnd {
                            break;
                        }
                        self.zip.reserve(self.zip.len().max(1024));
                    }
                }
                self.raw.clear();
                let n = bytes.len() as u64;
                let head: [u64; 4] = [u64::from(n > 0), n, n, self.zip.len() as u64];
                let hl = if n > 0 { 4 } else { 3 };
                for h in &head[..hl] {
                    self.raw.extend_from_slice(&h.to_le_bytes());
                }
                B64.encode_string(&self.raw, x);
                B64.encode_string(&self.zip, x);
            }
        }
        x.push_str("\n</DataArray>\n");
    }
}

/// The little-endian bytes of an `f64` slice (every supported target is little-endian;
/// checked at compile time below), by bytemuck's checked cast: the crate has no
/// `unsafe` of its own.
pub(super) fn bytemuck_f64(v: &[f64]) -> &[u8] {
    const _: () = assert!(cfg!(target_endian = "little"));
    bytemuck::cast_slice(v)
}
