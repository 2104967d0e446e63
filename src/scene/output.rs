//! The `[output]` table of a scene, bar or plane, and the sampling of the profile file it
//! sets: the kept steps and the written nodes, bounded by default.

use crate::scene::SceneError;
use crate::scene::error::invalid;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Keep every `every`-th step in `displacement.csv` (the last step is always kept).
    #[serde(default = "one")]
    pub every: u64,
    /// Measure the energy balance (an extra pass over the bar) at every `diagnostics_every`-th
    /// step and at the last; the contact state is recorded at every step regardless.
    #[serde(default = "one")]
    pub diagnostics_every: u64,
    /// Nodes written at each kept step of `displacement.csv`, evenly strided, both ends always
    /// included. Unset: every node, unless that would write more than `max_rows` rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<u64>,
    /// The bound on the rows of `displacement.csv` when `nodes` is unset (about 40 MB of text
    /// at the default); raise it, or set `nodes`, to write more.
    #[serde(default = "default_max_rows")]
    pub max_rows: u64,
    /// The profile file's format: `displacement.csv`, or `displacement.npy` (the cargo feature
    /// `npy`). Left out of the printed scene when it is the default.
    #[serde(default, skip_serializing_if = "OutputFormat::is_csv")]
    pub format: OutputFormat,
}

/// `[output] format`: how the displacement profiles are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// `displacement.csv`: text, `t,x,u,v`.
    #[default]
    Csv,
    /// `displacement.npy`: a structured array `t, x, u, v` of `<f8` (cargo feature `npy`).
    Npy,
    /// ParaView: `solution.pvd`, a collection of one `vtu/step-N.vtu` per kept step (plane
    /// scenes; cargo feature `vtk`, on by default).
    Vtu,
}

impl OutputFormat {
    fn is_csv(&self) -> bool {
        *self == OutputFormat::Csv
    }

    /// The profile file's name.
    pub fn file(self) -> &'static str {
        match self {
            OutputFormat::Csv => "displacement.csv",
            OutputFormat::Npy => "displacement.npy",
            OutputFormat::Vtu => "solution.pvd",
        }
    }

    /// `csv`, `npy` or `vtu`, as in the scene.
    pub fn name(self) -> &'static str {
        match self {
            OutputFormat::Csv => "csv",
            OutputFormat::Npy => "npy",
            OutputFormat::Vtu => "vtu",
        }
    }

    /// The folder a format writes beside its file (`vtu/` of [`OutputFormat::Vtu`]).
    pub fn folder(self) -> Option<&'static str> {
        (self == OutputFormat::Vtu).then_some("vtu")
    }

    /// Refuses `npy` in a build without the `npy` feature, naming `output.format`.
    pub fn check_available(self) -> Result<(), SceneError> {
        if self == OutputFormat::Npy && !cfg!(feature = "npy") {
            return Err(SceneError::Invalid {
                field: "output.format".into(),
                value: "\"npy\"".into(),
                allowed: "this build has no npy writer: build with the cargo feature `npy` \
                          (`cargo run --release --features npy -- run ...`), or use \"csv\""
                    .into(),
            });
        }
        if self == OutputFormat::Vtu && !cfg!(feature = "vtk") {
            return Err(SceneError::Invalid {
                field: "output.format".into(),
                value: "\"vtu\"".into(),
                allowed: "this build has no VTK writer: build with the cargo feature `vtk` (on \
                          by default), or use \"csv\""
                    .into(),
            });
        }
        Ok(())
    }
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            every: 1,
            diagnostics_every: 1,
            nodes: None,
            max_rows: DEFAULT_MAX_ROWS,
            format: OutputFormat::Csv,
        }
    }
}

/// Default bound on the rows of `displacement.csv` (`[output] max_rows`).
pub const DEFAULT_MAX_ROWS: u64 = 1_000_000;

fn default_max_rows() -> u64 {
    DEFAULT_MAX_ROWS
}

/// What the profile file holds: the kept steps and the written nodes (reported in
/// summary.json as `output`, with the file's name and format).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OutputSampling {
    /// The profile file (`displacement.csv` or `displacement.npy`).
    pub file: &'static str,
    pub format: OutputFormat,
    /// Every `every`-th step is kept, and `t = 0` and the last step.
    pub every: u64,
    /// Every `node_stride`-th node is written, and the last node.
    pub node_stride: u64,
    pub kept_steps: u64,
    pub nodes_written: u64,
    pub rows: u64,
}

impl OutputSampling {
    /// Whether node `i` of `nodes` on a line is written.
    pub fn writes_node(&self, i: usize, nodes: usize) -> bool {
        (i as u64).is_multiple_of(self.node_stride) || i + 1 == nodes
    }
}

/// The nodes of one axis of `count` written with `stride`: every `stride`-th and the last.
pub fn written_on_axis(count: u64, stride: u64) -> u64 {
    match count {
        0 => 0,
        c => (c - 1) / stride + 1 + u64::from(!(c - 1).is_multiple_of(stride)),
    }
}

impl OutputSpec {
    /// Checks every field against its range; the error names the field.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.every < 1 {
            return Err(invalid("output.every", self.every as f64, "must be >= 1"));
        }
        if self.diagnostics_every < 1 {
            return Err(invalid(
                "output.diagnostics_every",
                self.diagnostics_every as f64,
                "must be >= 1",
            ));
        }
        if let Some(n) = self.nodes
            && n < 2
        {
            return Err(invalid(
                "output.nodes",
                n as f64,
                "must be >= 2 (both ends are always written)",
            ));
        }
        if self.max_rows < 2 {
            return Err(invalid(
                "output.max_rows",
                self.max_rows as f64,
                "must be >= 2",
            ));
        }
        self.format.check_available()?;
        Ok(())
    }

    /// The sampling of the profile file for a run of `steps` steps on a lattice of nodes
    /// (`[along x, along y]`): the kept steps (`every`), and the nodes (`nodes`, or all of them
    /// unless the rows would pass `max_rows`, then the fewest strided away that keep within
    /// it): every `node_stride`-th node along each axis and the last, so the edges are always
    /// written.
    pub fn sampling(&self, steps: u64, lattice: [u64; 2]) -> OutputSampling {
        let every = self.every;
        let kept_steps = 1 + steps / every + u64::from(!steps.is_multiple_of(every));
        let nodes = lattice[0] * lattice[1];
        let written = |s: u64| written_on_axis(lattice[0], s) * written_on_axis(lattice[1], s);
        let wanted = match self.nodes {
            Some(n) => n.min(nodes),
            None if kept_steps.saturating_mul(nodes) <= self.max_rows => nodes,
            None => (self.max_rows / kept_steps).clamp(2, nodes),
        };
        // The smallest stride writing at most `wanted` nodes (written(s) does not grow with s),
        // or the largest stride, which writes the ends of each axis only.
        let (mut lo, mut hi) = (1, lattice[0].max(lattice[1]).max(2) - 1);
        if written(hi) <= wanted {
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if written(mid) <= wanted {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
        }
        let stride = hi;
        let nodes_written = written(stride);
        OutputSampling {
            file: self.format.file(),
            format: self.format,
            every,
            node_stride: stride,
            kept_steps,
            nodes_written,
            rows: kept_steps * nodes_written,
        }
    }
}

fn one() -> u64 {
    1
}
