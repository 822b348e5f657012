//! Checksums that tell whether a basin file reads back as written: the header's digest and one
//! digest per chunk block (64-bit FNV-1a).

use hdf5::File;

use super::BasinHeader;

/// The root attribute `header_digest`: 64-bit FNV-1a (as [`block_digest`]) over every field of
/// the header a reader trusts — the run attributes (command, model, slope, params, resolved
/// model, integrator, tolerances, stride budget), the grid axes' names and values (f64 bits),
/// the state names, the legend (in code order) and the shard — each length-prefixed so that no two headers
/// frame to the same bytes. Written when the file is created, checked by every read of the
/// header (the explorer, `--resume`, `merge`).
pub(crate) fn header_digest(h: &BasinHeader) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut d: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in (bytes.len() as u64).to_le_bytes().iter().chain(bytes) {
            d ^= b as u64;
            d = d.wrapping_mul(PRIME);
        }
    };
    for text in [
        &h.command,
        &h.model,
        &h.params,
        &h.model_resolved,
        &h.integrator,
        &h.tolerances,
        &h.x_name,
        &h.y_name,
    ] {
        eat(text.as_bytes());
    }
    eat(&h.slope.to_bits().to_le_bytes());
    eat(&h.max_strides.to_le_bytes());
    let bits =
        |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect() };
    eat(&bits(&h.x));
    eat(&bits(&h.y));
    if let Some(z) = &h.z {
        eat(z.name.as_bytes());
        eat(&bits(&z.values));
    }
    for n in &h.state_names {
        eat(n.as_bytes());
    }
    // in code order: the file keeps the legend as a JSON object, which does not keep the order
    let mut legend = h.legend.clone();
    legend.sort();
    for (code, name) in &legend {
        eat(&[*code]);
        eat(name.as_bytes());
    }
    if let Some(sh) = h.shard {
        eat(&(sh.index as u64).to_le_bytes());
        eat(&(sh.count as u64).to_le_bytes());
    }
    d
}

/// What `/basin/block_digest` holds.
pub(super) const DIGEST_DESCRIPTION: &str =
    "per block of BLOCK_ROWS rows: 64-bit FNV-1a of the block's \
     outcome bytes, strides (u16 little-endian) and final states (f64 bits little-endian), in \
     row-major order; 0 for a block not written. Checked on resume and merge: a block whose \
     values read back different from what was written is recomputed or refused";

/// 64-bit FNV-1a (Fowler–Noll–Vo) over a block's outcome codes, stride counts and final states
/// (little-endian bytes, row-major): end-to-end evidence that a block reads back as written,
/// whatever part of the file (data, chunk index, object headers) was damaged.
pub(crate) fn block_digest(outcome: &[u8], strides: &[u16], final_state: &[f64]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(PRIME);
        }
    };
    eat(outcome);
    for v in strides {
        eat(&v.to_le_bytes());
    }
    for v in final_state {
        eat(&v.to_bits().to_le_bytes());
    }
    h
}

/// `/basin/block_digest` of an open file of `blocks` chunk blocks ([`BasinHeader::blocks`]):
/// `Some(None)` for files written before it existed, `None` if it is there but cannot be read
/// whole (damage).
pub(crate) fn read_digests(f: &File, blocks: usize) -> Option<Option<Vec<u64>>> {
    let Ok(basin) = f.group("basin") else {
        return None;
    };
    if !basin.link_exists("block_digest") {
        return Some(None);
    }
    let v = basin
        .dataset("block_digest")
        .and_then(|d| d.read_raw::<u64>())
        .ok()?;
    (v.len() == blocks).then_some(Some(v))
}
