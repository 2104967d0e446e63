//! `displacement.npy` (cargo feature `npy`): the profile rows as a structured array of `<f8`
//! fields (the bar's `t, x, u, v`, the plane's `t, x, y, ux, uy, vx, vy`), through npyz, so that
//! `numpy.load` gives named columns. The shape is known before the first row (the sampling
//! fixes the row count), so the header is written once, up front.

use npyz::{DType, Deserialize, Serialize, TypeRead, TypeWrite, WriterBuilder};
use std::io::{BufWriter, Read, Write};

/// One row of `N` doubles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileRow<const N: usize>(pub [f64; N]);

/// The record dtype with `<f8` fields named `columns`.
pub fn dtype(columns: &[&str]) -> DType {
    let f8: npyz::TypeStr = "<f8".parse().expect("a valid type string");
    DType::Record(
        (columns.iter())
            .map(|name| npyz::Field {
                name: (*name).to_string(),
                dtype: DType::Plain(f8.clone()),
            })
            .collect(),
    )
}

/// Whether `dtype` is a record of `N` little-endian doubles.
fn check<const N: usize>(dtype: &DType) -> Result<(), npyz::DTypeError> {
    let f8 = DType::Plain("<f8".parse().expect("a valid type string"));
    match dtype {
        DType::Record(fields) if fields.len() == N && fields.iter().all(|f| f.dtype == f8) => {
            Ok(())
        }
        _ => Err(npyz::DTypeError::custom(format!(
            "a profile row is {N} fields of <f8, not {}",
            dtype.descr()
        ))),
    }
}

pub struct RowWriter<const N: usize>;

impl<const N: usize> TypeWrite for RowWriter<N> {
    type Value = ProfileRow<N>;

    fn write_one<W: Write>(&self, mut writer: W, row: &ProfileRow<N>) -> std::io::Result<()> {
        for v in row.0 {
            writer.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    }
}

pub struct RowReader<const N: usize>;

impl<const N: usize> TypeRead for RowReader<N> {
    type Value = ProfileRow<N>;

    fn read_one<R: Read>(&self, mut reader: R) -> std::io::Result<ProfileRow<N>> {
        let mut row = [0.0; N];
        for v in &mut row {
            let mut bytes = [0u8; 8];
            reader.read_exact(&mut bytes)?;
            *v = f64::from_le_bytes(bytes);
        }
        Ok(ProfileRow(row))
    }
}

impl<const N: usize> Serialize for ProfileRow<N> {
    type TypeWriter = RowWriter<N>;

    fn writer(dtype: &DType) -> Result<RowWriter<N>, npyz::DTypeError> {
        check::<N>(dtype).map(|()| RowWriter)
    }
}

impl<const N: usize> Deserialize for ProfileRow<N> {
    type TypeReader = RowReader<N>;

    fn reader(dtype: &DType) -> Result<RowReader<N>, npyz::DTypeError> {
        check::<N>(dtype).map(|()| RowReader)
    }
}

/// The npy file's writer, `N` columns a row.
pub struct ProfileNpy<const N: usize> {
    writer: npyz::NpyWriter<ProfileRow<N>, BufWriter<std::fs::File>>,
}

impl<const N: usize> ProfileNpy<N> {
    /// A file of `rows` rows with the columns `columns`.
    pub fn new(file: std::fs::File, columns: &[&str], rows: u64) -> std::io::Result<Self> {
        let writer = npyz::WriteOptions::new()
            .dtype(dtype(columns))
            .shape(&[rows])
            .writer(BufWriter::with_capacity(1 << 17, file))
            .begin_nd()?;
        Ok(Self { writer })
    }

    pub fn push(&mut self, row: [f64; N]) -> std::io::Result<()> {
        self.writer.push(&ProfileRow(row))
    }

    pub fn finish(self) -> std::io::Result<()> {
        self.writer.finish()
    }
}
