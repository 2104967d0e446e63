//! The profile file of a run, for either body: at each kept step, one row per written node,
//! its time, coordinates, displacement and velocity (`t,x,u,v` on the bar's line,
//! `t,x,y,ux,uy,vx,vy` on the plane; 0 at clamped degrees of freedom; the velocity is the
//! scheme's `(u^n − u^{n−1})/Δt` at `t_{n−1/2}`; a body with a temperature adds `theta`, the
//! scheme's `θ^{n−1/2}`). `displacement.csv` in text, or
//! `displacement.npy` (cargo feature `npy`), sampled as [`OutputSampling`] says.

use crate::output::text::{output_time, push_time, push_value};
use crate::scene::{OutputFormat, OutputSampling};
use crate::scheme::{Body, State};
use std::io::Write;

/// The written nodes of a lattice `[along x, along y]` with `stride`: every `stride`-th and
/// the last along each axis, row by row.
pub fn written_nodes(lattice: [usize; 2], stride: usize) -> Vec<usize> {
    let axis = |count: usize| {
        let mut v: Vec<usize> = (0..count).step_by(stride.max(1)).collect();
        if count > 0 && v.last() != Some(&(count - 1)) {
            v.push(count - 1);
        }
        v
    };
    let (xs, ys) = (axis(lattice[0]), axis(lattice[1]));
    ys.iter()
        .flat_map(|j| xs.iter().map(move |i| i + j * lattice[0]))
        .collect()
}

/// The columns of a body with `components` degrees of freedom per node (`theta`: with a
/// temperature).
pub fn columns(components: usize, theta: bool) -> &'static [&'static str] {
    if components == 1 && theta {
        &["t", "x", "u", "v", "theta"]
    } else if components == 1 {
        &["t", "x", "u", "v"]
    } else if theta {
        &["t", "x", "y", "ux", "uy", "vx", "vy", "theta"]
    } else {
        &["t", "x", "y", "ux", "uy", "vx", "vy"]
    }
}

enum Writer {
    Csv {
        file: std::io::BufWriter<std::fs::File>,
        /// The coordinates' text of each written node, `x,` or `x,y,`.
        points: Vec<Vec<u8>>,
        row: Vec<u8>,
    },
    #[cfg(feature = "npy")]
    Line(crate::output::npy::ProfileNpy<4>, Vec<[f64; 2]>),
    #[cfg(feature = "npy")]
    LineTheta(crate::output::npy::ProfileNpy<5>, Vec<[f64; 2]>),
    #[cfg(feature = "npy")]
    Plane(crate::output::npy::ProfileNpy<7>, Vec<[f64; 2]>),
    #[cfg(feature = "npy")]
    PlaneTheta(crate::output::npy::ProfileNpy<8>, Vec<[f64; 2]>),
}

/// The profile file's writer.
pub struct Profiles {
    writer: Writer,
    nodes: Vec<usize>,
    components: usize,
    /// The unknown of each written degree of freedom (`None`: clamped, written as 0).
    unknowns: Vec<Option<usize>>,
    /// Whether a column `theta` follows.
    theta: bool,
}

impl Profiles {
    /// Writes the header into `file` (an `npy` scene in a build without the feature is
    /// refused before a run creates anything; `Unsupported` here all the same).
    pub fn new<B: Body>(
        file: std::fs::File,
        body: &B,
        sampling: &OutputSampling,
    ) -> std::io::Result<Self> {
        let theta = body.has_temperature();
        let stride = usize::try_from(sampling.node_stride).unwrap_or(usize::MAX);
        let nodes = written_nodes(body.lattice(), stride);
        let components = body.components();
        let unknowns = (nodes.iter())
            .flat_map(|&i| (0..components).map(move |c| components * i + c))
            .map(|dof| body.unknown_of(dof))
            .collect();
        let rounded = |i: usize| {
            let (x, y) = body.point(i);
            [output_time(x), y.map_or(0.0, output_time)]
        };
        let writer = match sampling.format {
            OutputFormat::Csv => {
                let mut file = std::io::BufWriter::with_capacity(1 << 17, file);
                writeln!(file, "{}", columns(components, theta).join(","))?;
                let points = (nodes.iter())
                    .map(|&i| {
                        let (x, y) = body.point(i);
                        let mut text = Vec::new();
                        for coordinate in std::iter::once(x).chain(y) {
                            push_time(coordinate, &mut text);
                            text.push(b',');
                        }
                        text
                    })
                    .collect();
                Writer::Csv {
                    file,
                    points,
                    row: Vec::new(),
                }
            }
            #[cfg(feature = "npy")]
            OutputFormat::Npy => {
                use crate::output::npy::ProfileNpy;
                let points = nodes.iter().map(|&i| rounded(i)).collect();
                let cols = columns(components, theta);
                if theta && components == 1 {
                    Writer::LineTheta(ProfileNpy::new(file, cols, sampling.rows)?, points)
                } else if theta {
                    Writer::PlaneTheta(ProfileNpy::new(file, cols, sampling.rows)?, points)
                } else if components == 1 {
                    Writer::Line(ProfileNpy::new(file, cols, sampling.rows)?, points)
                } else {
                    Writer::Plane(ProfileNpy::new(file, cols, sampling.rows)?, points)
                }
            }
            OutputFormat::Vtu => {
                let _ = rounded;
                return Err(std::io::Error::new(
                    std::io::ErrorKind::Unsupported,
                    "output.format = \"vtu\" is written as ParaView files, not as a table",
                ));
            }
            #[cfg(not(feature = "npy"))]
            OutputFormat::Npy => {
                let _ = rounded;
                return Err(std::io::Error::new(
                    std::io::ErrorKind::Unsupported,
                    "output.format = \"npy\" needs the cargo feature `npy`",
                ));
            }
        };
        Ok(Self {
            writer,
            nodes,
            components,
            unknowns,
            theta,
        })
    }

    /// The rows of one kept step at time `t` of `body`.
    pub fn write<B: Body>(&mut self, t: f64, state: State<'_>, body: &B) -> std::io::Result<()> {
        let theta = |j: usize| body.temperature(state.u, self.nodes[j]).unwrap_or(0.0);
        let k = self.components;
        let value = |dof: usize| match self.unknowns[dof] {
            Some(i) => (state.u[i], state.w[i] * state.scale),
            None => (0.0, 0.0),
        };
        match &mut self.writer {
            Writer::Csv { file, points, row } => {
                let mut t_text = Vec::new();
                push_time(t, &mut t_text);
                t_text.push(b',');
                for (j, point) in points.iter().enumerate() {
                    row.clear();
                    row.extend_from_slice(&t_text);
                    row.extend_from_slice(point);
                    for c in 0..k {
                        push_value(value(k * j + c).0, row);
                        row.push(b',');
                    }
                    for c in 0..k {
                        push_value(value(k * j + c).1, row);
                        row.push(if c + 1 == k && !self.theta {
                            b'\n'
                        } else {
                            b','
                        });
                    }
                    if self.theta {
                        push_value(theta(j), row);
                        row.push(b'\n');
                    }
                    file.write_all(row)?;
                }
            }
            #[cfg(feature = "npy")]
            Writer::Line(npy, points) => {
                let t = output_time(t);
                for (j, p) in points.iter().enumerate() {
                    let (u, v) = value(j);
                    npy.push([t, p[0], u, v])?;
                }
            }
            #[cfg(feature = "npy")]
            Writer::LineTheta(npy, points) => {
                let t = output_time(t);
                for (j, p) in points.iter().enumerate() {
                    let (u, v) = value(j);
                    npy.push([t, p[0], u, v, theta(j)])?;
                }
            }
            #[cfg(feature = "npy")]
            Writer::Plane(npy, points) => {
                let t = output_time(t);
                for (j, p) in points.iter().enumerate() {
                    let ((ux, vx), (uy, vy)) = (value(2 * j), value(2 * j + 1));
                    npy.push([t, p[0], p[1], ux, uy, vx, vy])?;
                }
            }
            #[cfg(feature = "npy")]
            Writer::PlaneTheta(npy, points) => {
                let t = output_time(t);
                for (j, p) in points.iter().enumerate() {
                    let ((ux, vx), (uy, vy)) = (value(2 * j), value(2 * j + 1));
                    npy.push([t, p[0], p[1], ux, uy, vx, vy, theta(j)])?;
                }
            }
        }
        Ok(())
    }

    /// Flushes the file.
    pub fn finish(self) -> std::io::Result<()> {
        match self.writer {
            Writer::Csv { mut file, .. } => file.flush(),
            #[cfg(feature = "npy")]
            Writer::Line(npy, _) => npy.finish(),
            #[cfg(feature = "npy")]
            Writer::LineTheta(npy, _) => npy.finish(),
            #[cfg(feature = "npy")]
            Writer::Plane(npy, _) => npy.finish(),
            #[cfg(feature = "npy")]
            Writer::PlaneTheta(npy, _) => npy.finish(),
        }
    }

    /// The written nodes.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }
}
