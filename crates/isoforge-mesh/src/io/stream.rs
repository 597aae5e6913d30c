//! Mesh writers that take a mesh piece by piece ([`MeshWriter`], a [`MeshSink`]), so the
//! mesher's output goes to the file as it is made and is never held whole.
//!
//! Formats whose header counts what follows, or that list every vertex before the first
//! triangle, cannot be written in the order the mesher makes things (vertices and triangles
//! interleaved, counts known at the end). Their parts go to *spill files* instead:
//! unnamed temporary files (gone when closed, whatever ends the process) in a folder the
//! caller names, beside the output, so a large mesh costs disk there, not memory. At
//! [`MeshWriter::finish`] the header is written and the spills are copied after it:
//!
//! | format | as it comes | spilled |
//! | --- | --- | --- |
//! | binary STL | – | 50-byte triangle records (the header counts them) |
//! | ASCII STL | every facet | – |
//! | OBJ | `v` and `f` lines, interleaved (a vertex always before its first use) | – |
//! | PLY | – | vertices and faces (the header counts both) |
//! | 3MF | `<vertex>` elements, into the zip stream | triangles (they follow every vertex) |
//!
//! When the counts are known and vertices come first (a mesh already in memory), the
//! writer needs no spill: [`MeshWriter::ordered`].

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::Path;

use super::{MeshFormat, fmt_coord};
use crate::sink::MeshSink;

/// Spill files' buffers.
const SPILL_BUFFER: usize = 1 << 16;
/// Text is built in a string and written out in pieces of about this size.
const TEXT_CHUNK: usize = 1 << 16;

/// Binary STL: the 80-byte header (text, padded with spaces; never starting with "solid",
/// which would make readers take it for ASCII).
const STL_HEADER: &[u8; 80] =
    b"binary STL written by isoforge                                                  ";

/// A temporary file that takes bytes now and gives them back at the end.
struct Spill {
    file: BufWriter<File>,
}

impl Spill {
    fn new(folder: &Path) -> io::Result<Spill> {
        // Beside the output if the folder takes files; else (a device, a pipe's folder)
        // in the system's temporary folder.
        let file = tempfile::tempfile_in(folder).or_else(|_| tempfile::tempfile())?;
        Ok(Spill {
            file: BufWriter::with_capacity(SPILL_BUFFER, file),
        })
    }

    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.file.write_all(bytes)
    }

    /// The bytes written, from the start, in records of `N` bytes.
    fn replay<const N: usize>(
        self,
        mut each: impl FnMut(&[u8; N]) -> io::Result<()>,
    ) -> io::Result<()> {
        let mut file = self.file.into_inner().map_err(|e| e.into_error())?;
        file.seek(SeekFrom::Start(0))?;
        let mut reader = BufReader::with_capacity(SPILL_BUFFER, file);
        let mut record = [0u8; N];
        loop {
            match reader.read_exact(&mut record) {
                Ok(()) => each(&record)?,
                Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(()),
                Err(e) => return Err(e),
            }
        }
    }
}

/// Where a writer keeps what must wait.
enum Waiting {
    /// Counts known up front, vertices before triangles: nothing waits.
    Nothing,
    /// Spill files in this folder (created on first need).
    Folder(std::path::PathBuf),
}

/// A format's state while writing.
enum State<W: Write> {
    Stl {
        out: W,
        spill: Option<Spill>,
        count: u64,
    },
    StlAscii {
        out: BufWriter<W>,
    },
    Obj {
        out: BufWriter<W>,
    },
    Ply {
        out: BufWriter<W>,
        vertices: Option<Spill>,
        faces: Option<Spill>,
    },
    ThreeMf {
        zip: Box<zip::ZipWriter<zip::write::StreamWriter<W>>>,
        text: String,
        faces: Option<Spill>,
        in_triangles: bool,
    },
}

/// A mesh file written piece by piece (see the module doc).
pub struct MeshWriter<W: Write> {
    state: State<W>,
    waiting: Waiting,
    vertices: u64,
    triangles: u64,
}

fn zip_error(e: zip::result::ZipError) -> io::Error {
    io::Error::other(e.to_string())
}

impl<W: Write> MeshWriter<W> {
    /// A writer that takes vertices and triangles in any order (each vertex before its
    /// first triangle), spilling what must wait into unnamed files in `spill_folder`.
    pub fn streaming(format: MeshFormat, out: W, spill_folder: &Path) -> io::Result<Self> {
        Self::start(
            format,
            out,
            Waiting::Folder(spill_folder.to_path_buf()),
            None,
        )
    }

    /// A writer for a mesh whose counts are known, given all its vertices first: no spill.
    pub fn ordered(
        format: MeshFormat,
        out: W,
        vertices: usize,
        triangles: usize,
    ) -> io::Result<Self> {
        Self::start(
            format,
            out,
            Waiting::Nothing,
            Some([vertices as u64, triangles as u64]),
        )
    }

    fn start(
        format: MeshFormat,
        out: W,
        waiting: Waiting,
        counts: Option<[u64; 2]>,
    ) -> io::Result<Self> {
        let state = match format {
            MeshFormat::Stl => {
                let mut out = out;
                if let Some([_, t]) = counts {
                    write_stl_header(&mut out, t)?;
                }
                State::Stl {
                    out,
                    spill: None,
                    count: 0,
                }
            }
            MeshFormat::StlAscii => {
                let mut out = BufWriter::with_capacity(TEXT_CHUNK, out);
                writeln!(out, "solid isoforge")?;
                State::StlAscii { out }
            }
            MeshFormat::Obj => {
                let mut out = BufWriter::with_capacity(TEXT_CHUNK, out);
                writeln!(out, "# isoforge")?;
                if let Some([v, t]) = counts {
                    writeln!(out, "# {v} vertices, {t} triangles")?;
                }
                State::Obj { out }
            }
            MeshFormat::Ply => {
                let mut out = BufWriter::with_capacity(TEXT_CHUNK, out);
                if let Some(c) = counts {
                    write_ply_header(&mut out, c)?;
                }
                State::Ply {
                    out,
                    vertices: None,
                    faces: None,
                }
            }
            MeshFormat::ThreeMf => {
                let mut zip = zip::ZipWriter::new_stream(out);
                let deflate = zip::write::SimpleFileOptions::default()
                    .compression_method(zip::CompressionMethod::Deflated)
                    .compression_level(Some(super::threemf::DEFLATE_LEVEL));
                zip.start_file("[Content_Types].xml", deflate)
                    .map_err(zip_error)?;
                zip.write_all(super::threemf::CONTENT_TYPES.as_bytes())?;
                zip.start_file("_rels/.rels", deflate).map_err(zip_error)?;
                zip.write_all(super::threemf::RELS.as_bytes())?;
                // The model's size is not known while it streams: always allow ZIP64, or a
                // model part past 4 GiB could not be written.
                zip.start_file("3D/3dmodel.model", deflate.large_file(true))
                    .map_err(zip_error)?;
                let mut text = String::with_capacity(TEXT_CHUNK * 2);
                text.push_str(super::threemf::MODEL_HEAD);
                State::ThreeMf {
                    zip: Box::new(zip),
                    text,
                    faces: None,
                    in_triangles: false,
                }
            }
        };
        Ok(MeshWriter {
            state,
            waiting,
            vertices: 0,
            triangles: 0,
        })
    }

    fn spill(&self) -> io::Result<Spill> {
        match &self.waiting {
            Waiting::Folder(f) => Spill::new(f),
            Waiting::Nothing => Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "this writer was promised every vertex before the first triangle",
            )),
        }
    }

    /// Writes what waited and the format's ending; returns the output.
    pub fn finish(self) -> io::Result<W> {
        let ordered = matches!(self.waiting, Waiting::Nothing);
        let (vertices, triangles) = (self.vertices, self.triangles);
        match self.state {
            State::Stl {
                mut out,
                spill,
                count,
            } => {
                if !ordered {
                    write_stl_header(&mut out, count)?;
                    if let Some(spill) = spill {
                        let mut buf = BufWriter::with_capacity(SPILL_BUFFER, &mut out);
                        spill.replay::<50>(|r| buf.write_all(r))?;
                        buf.flush()?;
                    }
                }
                out.flush()?;
                Ok(out)
            }
            State::StlAscii { mut out } => {
                writeln!(out, "endsolid isoforge")?;
                out.flush()?;
                out.into_inner().map_err(|e| e.into_error())
            }
            State::Obj { mut out } => {
                out.flush()?;
                out.into_inner().map_err(|e| e.into_error())
            }
            State::Ply {
                mut out,
                vertices: vs,
                faces,
                ..
            } => {
                if !ordered {
                    write_ply_header(&mut out, [vertices, triangles])?;
                    if let Some(vs) = vs {
                        vs.replay::<12>(|r| out.write_all(r))?;
                    }
                    if let Some(faces) = faces {
                        faces.replay::<12>(|r| {
                            out.write_all(&[3])?;
                            out.write_all(r)
                        })?;
                    }
                }
                out.flush()?;
                out.into_inner().map_err(|e| e.into_error())
            }
            State::ThreeMf {
                mut zip,
                mut text,
                faces,
                in_triangles,
            } => {
                if !in_triangles {
                    text.push_str("</vertices>\n<triangles>\n");
                }
                if let Some(faces) = faces {
                    faces.replay::<12>(|r| {
                        let t: [u32; 3] = std::array::from_fn(|k| {
                            u32::from_le_bytes([r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 3]])
                        });
                        push_triangle_xml(&mut text, t);
                        if text.len() > TEXT_CHUNK {
                            zip.write_all(text.as_bytes())?;
                            text.clear();
                        }
                        Ok(())
                    })?;
                }
                text.push_str(super::threemf::MODEL_TAIL);
                zip.write_all(text.as_bytes())?;
                let mut out = zip.finish().map_err(zip_error)?.into_inner();
                out.flush()?;
                Ok(out)
            }
        }
    }
}

impl<W: Write> MeshSink for MeshWriter<W> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.vertices += 1;
        let need_spill = match &self.state {
            State::Ply { vertices, .. } => vertices.is_none(),
            _ => false,
        } && !matches!(self.waiting, Waiting::Nothing);
        let new_spill = if need_spill {
            Some(self.spill()?)
        } else {
            None
        };
        match &mut self.state {
            State::Stl { .. } | State::StlAscii { .. } => Ok(()),
            State::Obj { out } => writeln!(
                out,
                "v {} {} {}",
                fmt_coord(p[0]),
                fmt_coord(p[1]),
                fmt_coord(p[2])
            ),
            State::Ply { out, vertices, .. } => {
                let bytes = vertex_bytes(p);
                if let Some(s) = new_spill {
                    *vertices = Some(s);
                }
                match vertices {
                    Some(s) => s.write(&bytes),
                    None => out.write_all(&bytes),
                }
            }
            State::ThreeMf {
                zip,
                text,
                in_triangles,
                ..
            } => {
                if *in_triangles {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidInput,
                        "a vertex after the triangles began",
                    ));
                }
                let _ = writeln!(
                    text,
                    "<vertex x=\"{}\" y=\"{}\" z=\"{}\"/>",
                    fmt_coord(p[0]),
                    fmt_coord(p[1]),
                    fmt_coord(p[2])
                );
                if text.len() > TEXT_CHUNK {
                    zip.write_all(text.as_bytes())?;
                    text.clear();
                }
                Ok(())
            }
        }
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.triangles += 1;
        let ordered = matches!(self.waiting, Waiting::Nothing);
        let need_spill = !ordered
            && match &self.state {
                State::Stl { spill, .. } => spill.is_none(),
                State::Ply { faces, .. } => faces.is_none(),
                State::ThreeMf { faces, .. } => faces.is_none(),
                _ => false,
            };
        let new_spill = if need_spill {
            Some(self.spill()?)
        } else {
            None
        };
        match &mut self.state {
            State::Stl { out, spill, count } => {
                *count += 1;
                let record = stl_record(corners);
                if let Some(s) = new_spill {
                    *spill = Some(s);
                }
                match spill {
                    Some(s) => s.write(&record),
                    None => out.write_all(&record),
                }
            }
            State::StlAscii { out } => write_ascii_facet(out, corners),
            State::Obj { out } => writeln!(out, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1),
            State::Ply { out, faces, .. } => {
                let mut bytes = [0u8; 12];
                for k in 0..3 {
                    // PLY `int` indices: past i32::MAX is beyond what readers could load.
                    let i = i32::try_from(t[k]).map_err(|_| {
                        io::Error::new(
                            io::ErrorKind::InvalidInput,
                            "vertex index too large for PLY int",
                        )
                    })?;
                    bytes[4 * k..4 * k + 4].copy_from_slice(&i.to_le_bytes());
                }
                if let Some(s) = new_spill {
                    *faces = Some(s);
                }
                match faces {
                    Some(s) => s.write(&bytes),
                    None => {
                        out.write_all(&[3])?;
                        out.write_all(&bytes)
                    }
                }
            }
            State::ThreeMf {
                zip,
                text,
                faces,
                in_triangles,
            } => {
                if let Some(s) = new_spill {
                    *faces = Some(s);
                }
                match faces {
                    Some(s) => {
                        let mut bytes = [0u8; 12];
                        for k in 0..3 {
                            bytes[4 * k..4 * k + 4].copy_from_slice(&t[k].to_le_bytes());
                        }
                        s.write(&bytes)
                    }
                    None => {
                        if !*in_triangles {
                            text.push_str("</vertices>\n<triangles>\n");
                            *in_triangles = true;
                        }
                        push_triangle_xml(text, t);
                        if text.len() > TEXT_CHUNK {
                            zip.write_all(text.as_bytes())?;
                            text.clear();
                        }
                        Ok(())
                    }
                }
            }
        }
    }
}

fn write_stl_header(out: &mut impl Write, count: u64) -> io::Result<()> {
    let count = u32::try_from(count).map_err(|_| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "more than 4,294,967,295 triangles: binary STL cannot count them",
        )
    })?;
    out.write_all(STL_HEADER)?;
    out.write_all(&count.to_le_bytes())
}

fn write_ply_header(out: &mut impl Write, [v, t]: [u64; 2]) -> io::Result<()> {
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment isoforge\n\
         element vertex {v}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {t}\nproperty list uchar int vertex_indices\nend_header\n",
    )
}

/// Little-endian f32s, `-0.0` written as `0.0` (readers weld by bit pattern).
fn vertex_bytes(p: [f32; 3]) -> [u8; 12] {
    let mut b = [0u8; 12];
    for k in 0..3 {
        b[4 * k..4 * k + 4].copy_from_slice(&(p[k] + 0.0).to_le_bytes());
    }
    b
}

/// The unit normal of a triangle from its winding (zero when degenerate).
fn normal(c: [[f32; 3]; 3]) -> [f32; 3] {
    use glam::Vec3;
    let [a, b, d] = c.map(|p| Vec3::from(p).as_dvec3());
    let n = (b - a).cross(d - a);
    let len = n.length();
    if len > 0.0 && len.is_finite() {
        (n / len).as_vec3().to_array()
    } else {
        [0.0; 3]
    }
}

/// A binary STL record: normal, three corners, a zero attribute.
fn stl_record(corners: [[f32; 3]; 3]) -> [u8; 50] {
    let mut r = [0u8; 50];
    let n = normal(corners);
    for (k, v) in n.iter().chain(corners.iter().flatten()).enumerate() {
        r[4 * k..4 * k + 4].copy_from_slice(&(v + 0.0).to_le_bytes());
    }
    r
}

fn write_ascii_facet(out: &mut impl Write, corners: [[f32; 3]; 3]) -> io::Result<()> {
    let n = normal(corners);
    writeln!(
        out,
        "  facet normal {} {} {}",
        fmt_coord(n[0]),
        fmt_coord(n[1]),
        fmt_coord(n[2])
    )?;
    writeln!(out, "    outer loop")?;
    for p in corners {
        writeln!(
            out,
            "      vertex {} {} {}",
            fmt_coord(p[0]),
            fmt_coord(p[1]),
            fmt_coord(p[2])
        )?;
    }
    writeln!(out, "    endloop")?;
    writeln!(out, "  endfacet")
}

fn push_triangle_xml(text: &mut String, t: [u32; 3]) {
    let _ = writeln!(
        text,
        "<triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"/>",
        t[0], t[1], t[2]
    );
}
