//! Where the rows of a basin grid lie in its datasets: chunk blocks of [`BLOCK_ROWS`] rows,
//! within one z-slice of a 3-D grid.

use hdf5::Dataset;

use super::{BasinHeader, BLOCK_ROWS};

/// Chunk blocks of a grid of `nz` slices of `ny` rows: each slice is cut into blocks of
/// [`BLOCK_ROWS`] rows (the last one shorter), so that no block spans two slices and each is
/// one chunk of the datasets.
pub fn block_count(ny: usize, nz: usize) -> usize {
    nz * ny.div_ceil(BLOCK_ROWS)
}

/// The chunk block holding row `r` (row `k·ny + i` is slice k, row i) of a grid of `ny` rows
/// per slice: `r / BLOCK_ROWS` for a 2-D grid.
pub fn block_of(r: usize, ny: usize) -> usize {
    (r / ny) * ny.div_ceil(BLOCK_ROWS) + (r % ny) / BLOCK_ROWS
}

/// Rows (as writer rows, `k·ny + i`) of chunk block `b` of a grid of `ny` rows per slice.
pub fn block_range(b: usize, ny: usize) -> std::ops::Range<usize> {
    let per_slice = ny.div_ceil(BLOCK_ROWS);
    let (k, j) = (b / per_slice, b % per_slice);
    k * ny + j * BLOCK_ROWS..k * ny + ((j + 1) * BLOCK_ROWS).min(ny)
}

/// Where a chunk block's cells are in the datasets: `[rows, nx(, d)]` for a 2-D grid,
/// `[1, rows, nx(, d)]` within its z-slice for a 3-D one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    ny: usize,
    three_d: bool,
}

impl Layout {
    pub(crate) fn of(h: &BasinHeader) -> Self {
        Layout {
            ny: h.ny(),
            three_d: h.z.is_some(),
        }
    }

    /// Block `b` of a dataset whose cells have the trailing dimensions `trailing` (`[nx]`,
    /// `[nx, d]`): its hyperslab and its shape.
    fn block(&self, b: usize, trailing: &[usize]) -> (hdf5::Selection, Vec<usize>) {
        use hdf5::SliceOrIndex;
        let r = block_range(b, self.ny);
        let mut sel: Vec<SliceOrIndex> = Vec::new();
        let mut shape = Vec::new();
        if self.three_d {
            let k = r.start / self.ny;
            sel.push((k..k + 1).into());
            sel.push((r.start - k * self.ny..r.end - k * self.ny).into());
            shape.push(1);
        } else {
            sel.push(r.clone().into());
        }
        shape.push(r.len());
        for &t in trailing {
            sel.push((..).into());
            shape.push(t);
        }
        (hdf5::Selection::new(hdf5::Hyperslab::from(sel)), shape)
    }

    /// The values of block `b` of `ds`, row-major.
    pub(crate) fn read<T: hdf5::H5Type + Copy>(
        &self,
        ds: &Dataset,
        b: usize,
        trailing: &[usize],
    ) -> hdf5::Result<Vec<T>> {
        let (sel, _) = self.block(b, trailing);
        let a = ds.read_slice::<T, _, ndarray::IxDyn>(sel)?;
        Ok(a.iter().copied().collect())
    }

    /// Writes block `b` of `ds` from its values, row-major.
    pub(super) fn write<T: hdf5::H5Type>(
        &self,
        ds: &Dataset,
        b: usize,
        trailing: &[usize],
        v: &[T],
    ) -> hdf5::Result<()> {
        let (sel, shape) = self.block(b, trailing);
        let a = ndarray::ArrayViewD::from_shape(ndarray::IxDyn(&shape), v)
            .map_err(|e| hdf5::Error::from(e.to_string()))?;
        ds.write_slice(a, sel)
    }

    /// The shape of a whole dataset whose cells have the trailing dimensions `trailing`, and
    /// its chunk (one block).
    pub(super) fn dataset(&self, nz: usize, trailing: &[usize]) -> (Vec<usize>, Vec<usize>) {
        let rb = BLOCK_ROWS.min(self.ny);
        let (mut shape, mut chunk) = if self.three_d {
            (vec![nz, self.ny], vec![1, rb])
        } else {
            (vec![self.ny], vec![rb])
        };
        shape.extend_from_slice(trailing);
        chunk.extend_from_slice(trailing);
        (shape, chunk)
    }
}
