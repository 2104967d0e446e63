//! The kept steps of a run: the profile table (`displacement.csv`/`.npy`, [`Profiles`]) or, with
//! `[output] format = "vtu"` (plane scenes, cargo feature `vtk`), ParaView files: one
//! `vtu/step-N.vtu` per kept step (VTK XML unstructured grid of Q1 quads, written by vtkio) and
//! `solution.pvd`, the collection with their times. The written nodes are the profile's
//! (`[output] every`, `nodes`, `max_rows`): every `node_stride`-th node along each axis and the
//! last, joined into quads. Point data: `displacement`, `velocity` (`(u^n − u^{n−1})/Δt`),
//! `sigma_xx`, `sigma_yy`, `sigma_xy`, `von_mises` (nodal area-weighted means of the cell-centre
//! Kelvin–Voigt stress, [`crate::plane::stress`]), `contact_reaction` (the obstacles' normal
//! force `Σ_k r_k s_k e_{c_k}` at the node), `contact_force` (that plus a frictional node's
//! tangential reaction `r_T t`), `friction_state` ([`crate::scheme::NodeState`]: 0 open or
//! frictionless, 1 stick, 2 slip), `gap` (the least gap of the node's constraints, 0 at a node
//! without one), `contact_constraints` (their number: 0, 1, or 2 at a corner) and, with
//! `[heat]`, `theta` (`θ^{n−1/2}`, as the profile file). At `t = 0` no step has acted: every reaction and state is 0.

use crate::output::profiles::Profiles;
#[cfg(feature = "vtk")]
use crate::scene::OutputFormat;
use crate::scene::OutputSampling;
use crate::scheme::contact::ContactSet;
use crate::scheme::{Body, RunError, Scheme, State};
use std::path::{Path, PathBuf};

/// What a kept step shows besides the state: the body, its constraints, their reactions and
/// the increments that classify its frictional nodes (all but the body read by the VTU writer
/// only).
#[cfg_attr(not(feature = "vtk"), allow(dead_code))]
pub struct Kept<'a, B> {
    pub body: &'a B,
    pub contact: &'a ContactSet,
    /// One per constraint.
    pub reactions: &'a [f64],
    /// One per frictional node.
    pub tangential: &'a [f64],
    /// [`Scheme::increments`]; `None` before the first step.
    pub increments: Option<[&'a [f64]; 2]>,
}

impl<'a, B: Body> Kept<'a, B> {
    /// The last step of `sim`.
    pub fn of(sim: &'a Scheme<B>) -> Self {
        Self {
            body: sim.body(),
            contact: sim.contact(),
            reactions: sim.reactions(),
            tangential: sim.tangential_reactions(),
            increments: Some(sim.increments()),
        }
    }
}

/// The writer of a run's kept steps.
pub enum KeptSteps {
    Table {
        profiles: Profiles,
        path: PathBuf,
    },
    #[cfg(feature = "vtk")]
    Vtu(Box<series::VtuSeries>),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Write {
        path: path.to_path_buf(),
        source,
    }
}

impl KeptSteps {
    /// The writer of `sampling`'s format into the folder `dir`.
    pub fn new<B: Body>(
        dir: &Path,
        body: &B,
        contact: &ContactSet,
        sampling: &OutputSampling,
    ) -> Result<Self, RunError> {
        match sampling.format {
            #[cfg(feature = "vtk")]
            OutputFormat::Vtu => Ok(KeptSteps::Vtu(Box::new(series::VtuSeries::new(
                dir, body, contact, sampling,
            )?))),
            _ => {
                let _ = contact;
                let path = dir.join(sampling.file);
                let file = std::fs::File::create(&path).map_err(io(&path))?;
                let profiles = Profiles::new(file, body, sampling).map_err(io(&path))?;
                Ok(KeptSteps::Table { profiles, path })
            }
        }
    }

    /// Writes step `step` at time `t`: the state, and for ParaView the stress, reactions and
    /// gaps.
    #[cfg_attr(not(feature = "vtk"), expect(unused_variables))]
    pub fn write<B: Body>(
        &mut self,
        step: usize,
        t: f64,
        state: State<'_>,
        kept: Kept<'_, B>,
    ) -> Result<(), RunError> {
        match self {
            KeptSteps::Table { profiles, path } => {
                profiles.write(t, state, kept.body).map_err(io(path))
            }
            #[cfg(feature = "vtk")]
            KeptSteps::Vtu(s) => s.write(step, t, state, kept),
        }
    }

    /// Flushes the table, or writes `solution.pvd`.
    pub fn finish(self) -> Result<(), RunError> {
        match self {
            KeptSteps::Table { profiles, path } => profiles.finish().map_err(io(&path)),
            #[cfg(feature = "vtk")]
            KeptSteps::Vtu(s) => s.finish(),
        }
    }
}

#[cfg(feature = "vtk")]
pub mod series {
    //! The ParaView writer ([`VtuSeries`]).

    use super::{Kept, io};
    use crate::output::profiles::written_nodes;
    use crate::output::text::push_time;
    use crate::plane::stress::von_mises;
    use crate::scene::{OutputSampling, written_on_axis};
    use crate::scheme::contact::ContactSet;
    use crate::scheme::{Body, RunError, State};
    use std::io::Write;
    use std::path::{Path, PathBuf};
    use vtkio::model::{
        Attribute, Attributes, ByteOrder, CellType, Cells, DataArrayBase, DataSet, ElementType,
        UnstructuredGridPiece, Version, VertexNumbers, Vtk,
    };

    /// The folder of the `.vtu` files, beside `solution.pvd`.
    pub const FOLDER: &str = "vtu";

    /// One `.vtu` per kept step and the collection of them.
    pub struct VtuSeries {
        dir: PathBuf,
        /// The written nodes, row by row, and their lattice `[along x, along y]`.
        nodes: Vec<usize>,
        lattice: [usize; 2],
        /// `x, y, 0` of each written node.
        points: Vec<f64>,
        /// The written node and component of each constraint (`None`: its node is not written).
        constraint_at: Vec<Option<(usize, usize)>>,
        /// The same of each frictional node's tangential unknown.
        tangent_at: Vec<Option<(usize, usize)>>,
        /// Digits of the step numbers in the file names (of a bound on the last step).
        width: usize,
        /// `solution.pvd`.
        file: &'static str,
        /// `(t, file)` of each file written.
        entries: Vec<(f64, String)>,
        gaps: Vec<f64>,
    }

    impl VtuSeries {
        pub fn new<B: Body>(
            dir: &Path,
            body: &B,
            contact: &ContactSet,
            sampling: &OutputSampling,
        ) -> Result<Self, RunError> {
            let folder = dir.join(FOLDER);
            std::fs::create_dir_all(&folder).map_err(io(&folder))?;
            let lattice = body.lattice();
            let stride = usize::try_from(sampling.node_stride).unwrap_or(usize::MAX);
            let nodes = written_nodes(lattice, stride);
            let axis = |count: usize| written_on_axis(count as u64, stride as u64) as usize;
            let written_lattice = [axis(lattice[0]), axis(lattice[1])];
            let mut written = vec![None; body.nodes()];
            let mut points = Vec::with_capacity(3 * nodes.len());
            for (w, &n) in nodes.iter().enumerate() {
                written[n] = Some(w);
                let (x, y) = body.point(n);
                points.extend([x, y.unwrap_or(0.0), 0.0]);
            }
            let k = body.components();
            let mut dof_of = vec![usize::MAX; body.unknowns()];
            for dof in 0..body.nodes() * k {
                if let Some(i) = body.unknown_of(dof) {
                    dof_of[i] = dof;
                }
            }
            let at = |unknown: usize| {
                let dof = dof_of[unknown];
                written[dof / k].map(|w| (w, dof % k))
            };
            let constraint_at = (0..contact.len()).map(|c| at(contact.unknown(c))).collect();
            let tangent_at = contact.friction().tangents.iter().map(|&t| at(t)).collect();
            Ok(Self {
                dir: dir.to_path_buf(),
                nodes,
                lattice: written_lattice,
                points,
                constraint_at,
                tangent_at,
                width: (sampling.kept_steps.saturating_sub(1) * sampling.every)
                    .to_string()
                    .len(),
                file: sampling.file,
                entries: Vec::new(),
                gaps: vec![0.0; contact.len()],
            })
        }

        /// `vtu/step-N.vtu` of step `step` at `t`.
        pub fn write<B: Body>(
            &mut self,
            step: usize,
            t: f64,
            state: State<'_>,
            kept: Kept<'_, B>,
        ) -> Result<(), RunError> {
            let (body, contact, reactions) = (kept.body, kept.contact, kept.reactions);
            let k = body.components();
            let v: Vec<f64> = state.w.iter().map(|w| w * state.scale).collect();
            let vector = |f: &[f64]| {
                let mut out = Vec::with_capacity(3 * self.nodes.len());
                for &n in &self.nodes {
                    for c in 0..3 {
                        let value = (c < k)
                            .then(|| body.unknown_of(k * n + c))
                            .flatten()
                            .map_or(0.0, |i| f[i]);
                        out.push(value);
                    }
                }
                out
            };
            let (displacement, velocity) = (vector(state.u), vector(&v));
            let stress = body.nodal_stress(state.u, &v).unwrap_or_default();
            let component = |j: usize| -> Vec<f64> {
                self.nodes
                    .iter()
                    .map(|&n| stress.get(n).map_or(0.0, |s| s[j]))
                    .collect()
            };
            let mises: Vec<f64> = (self.nodes.iter())
                .map(|&n| stress.get(n).map_or(0.0, |s| von_mises(*s)))
                .collect();
            contact.gaps_into(state.u, &mut self.gaps);
            let mut reaction = vec![0.0; 3 * self.nodes.len()];
            let mut gap = vec![0.0; self.nodes.len()];
            let mut count = vec![0.0; self.nodes.len()];
            for (c, at) in self.constraint_at.iter().enumerate() {
                let Some((w, component)) = *at else { continue };
                reaction[3 * w + component] += reactions[c] * contact.direction(c);
                gap[w] = if count[w] == 0.0 {
                    self.gaps[c]
                } else {
                    gap[w].min(self.gaps[c])
                };
                count[w] += 1.0;
            }
            // The normal part, then the tangential reactions and states of the frictional nodes.
            let mut force = reaction.clone();
            let mut friction_state = vec![0.0; self.nodes.len()];
            for (j, at) in self.tangent_at.iter().enumerate() {
                let Some((w, component)) = *at else { continue };
                force[3 * w + component] += kept.tangential[j];
                if let Some([z, w_before]) = kept.increments {
                    let node = contact.node_state(j, (state.u, z, w_before));
                    friction_state[w] = f64::from(node as u8);
                }
            }
            let scalar = |name: &str, data: Vec<f64>| {
                Attribute::DataArray(DataArrayBase {
                    name: name.into(),
                    elem: ElementType::Scalars {
                        num_comp: 1,
                        lookup_table: None,
                    },
                    data: data.into(),
                })
            };
            let vectors = |name: &str, data: Vec<f64>| {
                Attribute::DataArray(DataArrayBase {
                    name: name.into(),
                    elem: ElementType::Vectors,
                    data: data.into(),
                })
            };
            let theta: Option<Vec<f64>> = (self.nodes.iter())
                .map(|&n| body.temperature(state.u, n))
                .collect();
            let mut point = vec![
                vectors("displacement", displacement),
                vectors("velocity", velocity),
                scalar("sigma_xx", component(0)),
                scalar("sigma_yy", component(1)),
                scalar("sigma_xy", component(2)),
                scalar("von_mises", mises),
                vectors("contact_reaction", reaction),
                vectors("contact_force", force),
                scalar("friction_state", friction_state),
                scalar("gap", gap),
                scalar("contact_constraints", count),
            ];
            if let Some(theta) = theta {
                point.push(scalar("theta", theta));
            }
            let vtk = Vtk {
                version: Version::XML { major: 1, minor: 0 },
                byte_order: ByteOrder::LittleEndian,
                title: String::new(),
                file_path: None,
                data: DataSet::inline(UnstructuredGridPiece {
                    points: self.points.clone().into(),
                    cells: self.cells(),
                    data: Attributes {
                        point,
                        cell: Vec::new(),
                    },
                }),
            };
            let name = format!("{FOLDER}/step-{step:0width$}.vtu", width = self.width);
            let path = self.dir.join(&name);
            let file = std::fs::File::create(&path).map_err(io(&path))?;
            let mut file = std::io::BufWriter::new(file);
            vtk.write_xml(&mut file).map_err(|e| RunError::Write {
                path: path.clone(),
                source: std::io::Error::other(e.to_string()),
            })?;
            file.flush().map_err(io(&path))?;
            self.entries.push((t, name));
            Ok(())
        }

        /// The quads of the written lattice, counter-clockwise from the lower left.
        fn cells(&self) -> Cells {
            let [cols, rows] = self.lattice;
            let mut connectivity = Vec::new();
            let mut offsets = Vec::new();
            for j in 0..rows.saturating_sub(1) {
                for i in 0..cols.saturating_sub(1) {
                    let at = |i: usize, j: usize| (j * cols + i) as u64;
                    connectivity.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    offsets.push(connectivity.len() as u64);
                }
            }
            let types = vec![CellType::Quad; offsets.len()];
            Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets,
                },
                types,
            }
        }

        /// Writes `solution.pvd`: each file with its time (rounded as every output's times).
        pub fn finish(self) -> Result<(), RunError> {
            let mut text = String::from(
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
                 byte_order=\"LittleEndian\">\n  <Collection>\n",
            );
            for (t, file) in &self.entries {
                let mut time = Vec::new();
                push_time(*t, &mut time);
                text.push_str(&format!(
                    "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{file}\"/>\n",
                    String::from_utf8_lossy(&time)
                ));
            }
            text.push_str("  </Collection>\n</VTKFile>\n");
            let path = self.dir.join(self.file);
            std::fs::write(&path, text).map_err(io(&path))
        }
    }
}
