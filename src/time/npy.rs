//! `displacement.npy` (`[output] format = "npy"`, cargo feature `npy`): the rows of
//! `displacement.csv` as a structured array `t, x, u, v` of little-endian doubles (`<f8`),
//! which `numpy.load` and `pandas.DataFrame(numpy.load(...))` read directly. The header and the
//! row count are npyz's; the row count is known before the run, so the file is streamed.

use crate::time::simulation::NodeValues;
use npyz::{DType, Deserialize, Serialize, TypeRead, TypeWrite, WriterBuilder};
use std::io::{BufWriter, Read, Write};

/// One row of `displacement.npy`: `t` and `x` rounded as in `displacement.csv`
/// ([`crate::time::summary::output_time`]), `u` and `v` the simulation's own bits.
/// Read a file back with `npyz::NpyFile::new(reader)?.into_vec::<ProfileRow>()`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileRow {
    pub t: f64,
    pub x: f64,
    pub u: f64,
    pub v: f64,
}

/// The column names, in file order (those of `displacement.csv`).
pub const COLUMNS: [&str; 4] = ["t", "x", "u", "v"];

/// The file's dtype: `[('t', '<f8'), ('x', '<f8'), ('u', '<f8'), ('v', '<f8')]`.
pub fn dtype() -> DType {
    let f8: npyz::TypeStr = "<f8".parse().expect("a valid type string");
    DType::Record(
        COLUMNS
            .iter()
            .map(|name| npyz::Field {
                name: (*name).to_string(),
                dtype: DType::Plain(f8.clone()),
            })
            .collect(),
    )
}

fn check_dtype(dtype: &DType) -> Result<(), npyz::DTypeError> {
    if *dtype == self::dtype() {
        Ok(())
    } else {
        Err(npyz::DTypeError::custom(format!(
            "a profile row is {}, not {}",
            self::dtype().descr(),
            dtype.descr()
        )))
    }
}

/// Writes a row as four little-endian doubles (the dtype is checked in [`Serialize::writer`]).
pub struct ProfileRowWriter;

impl TypeWrite for ProfileRowWriter {
    type Value = ProfileRow;

    #[inline]
    fn write_one<W: Write>(&self, mut writer: W, r: &ProfileRow) -> std::io::Result<()> {
        let mut bytes = [0u8; 32];
        for (chunk, value) in bytes.chunks_exact_mut(8).zip([r.t, r.x, r.u, r.v]) {
            chunk.copy_from_slice(&value.to_le_bytes());
        }
        writer.write_all(&bytes)
    }
}

/// Reads a row written by [`ProfileRowWriter`].
pub struct ProfileRowReader;

impl TypeRead for ProfileRowReader {
    type Value = ProfileRow;

    #[inline]
    fn read_one<R: Read>(&self, mut reader: R) -> std::io::Result<ProfileRow> {
        let mut bytes = [0u8; 32];
        reader.read_exact(&mut bytes)?;
        let f = |k: usize| f64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().expect("8 bytes"));
        Ok(ProfileRow {
            t: f(0),
            x: f(1),
            u: f(2),
            v: f(3),
        })
    }
}

impl Serialize for ProfileRow {
    type TypeWriter = ProfileRowWriter;

    fn writer(dtype: &DType) -> Result<ProfileRowWriter, npyz::DTypeError> {
        check_dtype(dtype).map(|()| ProfileRowWriter)
    }
}

impl Deserialize for ProfileRow {
    type TypeReader = ProfileRowReader;

    fn reader(dtype: &DType) -> Result<ProfileRowReader, npyz::DTypeError> {
        check_dtype(dtype).map(|()| ProfileRowReader)
    }
}

impl npyz::AutoSerialize for ProfileRow {
    fn default_dtype() -> DType {
        dtype()
    }
}

/// Buffer of `displacement.npy` (32 bytes a row).
const NPY_BUFFER_BYTES: usize = 1 << 17;

/// The writer of `displacement.npy`: the header with the run's row count, then the rows of
/// each kept step.
pub(crate) struct ProfileNpy {
    writer: npyz::NpyWriter<ProfileRow, BufWriter<std::fs::File>>,
    /// The written nodes and their rounded `x`.
    nodes: Vec<(usize, f64)>,
}

impl ProfileNpy {
    /// Writes the header of an array of `rows` rows; `nodes` are the written nodes with their
    /// rounded `x`, in order.
    pub(crate) fn new(
        file: std::fs::File,
        rows: u64,
        nodes: Vec<(usize, f64)>,
    ) -> std::io::Result<Self> {
        let writer = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[rows])
            .writer(BufWriter::with_capacity(NPY_BUFFER_BYTES, file))
            .begin_nd()?;
        Ok(Self { writer, nodes })
    }

    /// The rows of one kept step at the rounded time `t`.
    pub(crate) fn write(&mut self, t: f64, values: NodeValues<'_>) -> std::io::Result<()> {
        for &(i, x) in &self.nodes {
            let (u, v) = values.at(i);
            self.writer.push(&ProfileRow { t, x, u, v })?;
        }
        Ok(())
    }

    /// Flushes the file; an error if the rows written are not the header's count.
    pub(crate) fn finish(self) -> std::io::Result<()> {
        self.writer.finish()
    }
}
