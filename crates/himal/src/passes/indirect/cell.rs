//! A cell of 8 x 8 radiance-transfer probes, its mips and its file format
//! (docs/techniques/L5.md "Cell files").

use std::path::Path;

use glam::Vec2;
use half::f16;

use crate::scene::world::SECTOR_SIZE;

/// Probes per cell along x and z.
pub const CELL_PROBES: usize = 8;
/// Probes per cell.
pub const PROBES_PER_CELL: usize = CELL_PROBES * CELL_PROBES;
/// Mip levels: mip m cells cover 2^m x 2^m sectors.
pub const MIPS: usize = 5;
/// Floats of one probe's transfer: 3 colour channels x 4 outgoing x 4 incoming SH coefficients.
pub const TRANSFER_FLOATS: usize = 3 * 4 * 4;
/// Sectors per axis of the probe grid (the world's 160 x 160 page table).
pub const GRID_SECTORS: i32 = 160;

/// File magic and version of a cell file.
pub const MAGIC: [u8; 4] = *b"HMLP";
/// Format version (bumped on any layout change; old files are re-baked).
pub const VERSION: u32 = 1;
const HEADER_BYTES: usize = 4 + 4 * 8;
/// Bytes of one cell file: header, heights (f32), transfer (f16), CRC-32.
pub const FILE_BYTES: usize =
    HEADER_BYTES + PROBES_PER_CELL * 4 + PROBES_PER_CELL * TRANSFER_FLOATS * 2 + 4;

/// Which cell: its mip and its column/row in that mip's grid (cells of
/// 2^mip sectors, counted from the grid's min corner).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellKey {
    /// 0..4.
    pub mip: u8,
    /// Column (west to east).
    pub x: i32,
    /// Row (north to south).
    pub z: i32,
}

impl CellKey {
    /// Side of the cell in metres (64 m x 2^mip).
    pub fn size(self) -> f32 {
        SECTOR_SIZE * (1u32 << self.mip) as f32
    }

    /// Distance between probes (8 m x 2^mip).
    pub fn spacing(self) -> f32 {
        self.size() / CELL_PROBES as f32
    }

    /// Min corner (x, z) in metres for a grid whose sector (0, 0) starts at `origin`.
    pub fn corner(self, origin: Vec2) -> Vec2 {
        origin + Vec2::new(self.x as f32, self.z as f32) * self.size()
    }

    /// The cell of mip `mip` that holds the sector `(sx, sz)`.
    pub fn of_sector(mip: u8, sx: i32, sz: i32) -> CellKey {
        CellKey {
            mip,
            x: sx >> mip,
            z: sz >> mip,
        }
    }

    /// The four cells of the mip below, in z-major order.
    pub fn children(self) -> [CellKey; 4] {
        let c = |dx, dz| CellKey {
            mip: self.mip - 1,
            x: self.x * 2 + dx,
            z: self.z * 2 + dz,
        };
        [c(0, 0), c(1, 0), c(0, 1), c(1, 1)]
    }

    /// File name of the cell in a cache directory.
    pub fn file_name(self) -> String {
        format!("m{}_{}_{}.hmlp", self.mip, self.x, self.z)
    }
}

/// One probe's radiance transfer: `m[c * 16 + i * 4 + j]` maps incoming
/// lighting coefficient j to the probe's bounced radiance coefficient i in
/// colour channel c.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transfer {
    /// Channel-major 3 x 4 x 4 matrix entries.
    pub m: [f32; TRANSFER_FLOATS],
}

impl Default for Transfer {
    fn default() -> Self {
        Transfer {
            m: [0.0; TRANSFER_FLOATS],
        }
    }
}

/// A cell: 8 x 8 probes, row-major (z then x), each at its height.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// Which cell.
    pub key: CellKey,
    /// Probe heights (y, metres), `[z * 8 + x]`.
    pub heights: [f32; PROBES_PER_CELL],
    /// Transfer per probe, same order as `heights`.
    pub probes: Vec<Transfer>,
}

impl Cell {
    /// World position (x, z) of probe (i, j) for a grid starting at `origin`.
    pub fn probe_xz(key: CellKey, origin: Vec2, i: usize, j: usize) -> Vec2 {
        key.corner(origin) + (Vec2::new(i as f32, j as f32) + 0.5) * key.spacing()
    }

    /// The cell of the next mip from its four children (`None`: outside
    /// the baked area); each probe is the mean of the 2 x 2 child probes it
    /// covers. Transfer is linear in lighting, so the mean of transfers is
    /// the transfer of the mean radiance.
    pub fn downsample(key: CellKey, children: [Option<&Cell>; 4]) -> Option<Cell> {
        if children.iter().all(Option::is_none) {
            return None;
        }
        let mut heights = [0.0; PROBES_PER_CELL];
        let mut probes = vec![Transfer::default(); PROBES_PER_CELL];
        let half = CELL_PROBES / 2;
        for j in 0..CELL_PROBES {
            for i in 0..CELL_PROBES {
                let child = children[(j / half) * 2 + i / half];
                let (ci, cj) = ((i % half) * 2, (j % half) * 2);
                let mut n = 0.0;
                let out = &mut probes[j * CELL_PROBES + i];
                if let Some(c) = child {
                    for (dx, dz) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let k = (cj + dz) * CELL_PROBES + ci + dx;
                        heights[j * CELL_PROBES + i] += c.heights[k];
                        for (o, v) in out.m.iter_mut().zip(c.probes[k].m) {
                            *o += v;
                        }
                        n += 1.0;
                    }
                } else {
                    // A missing child: take the nearest present probe's height, no light.
                    heights[j * CELL_PROBES + i] = children
                        .iter()
                        .flatten()
                        .next()
                        .map_or(0.0, |c| c.heights[0]);
                    continue;
                }
                heights[j * CELL_PROBES + i] /= n;
                out.m.iter_mut().for_each(|v| *v /= n);
            }
        }
        Some(Cell {
            key,
            heights,
            probes,
        })
    }

    /// The cell as a file: header (magic, version, mip, x, z, probes per
    /// axis, bounces, transfer floats, spacing), heights, transfer as f16,
    /// CRC-32 of everything before it. Little endian.
    pub fn encode(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(FILE_BYTES);
        b.extend_from_slice(&MAGIC);
        for v in [
            VERSION,
            self.key.mip as u32,
            self.key.x as u32,
            self.key.z as u32,
            CELL_PROBES as u32,
            1,
            TRANSFER_FLOATS as u32,
            self.key.spacing().to_bits(),
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for h in self.heights {
            b.extend_from_slice(&h.to_le_bytes());
        }
        for p in &self.probes {
            for v in p.m {
                b.extend_from_slice(&f16::from_f32(v).to_le_bytes());
            }
        }
        let crc = crc32fast::hash(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    /// Cell `key` from the cache file `path`; `None` where it is missing,
    /// damaged or another cell's (the caller bakes it again).
    pub fn read(path: &Path, key: CellKey) -> Option<Cell> {
        let bytes = std::fs::read(path).ok()?;
        Cell::decode(&bytes, path).ok().filter(|c| c.key == key)
    }

    /// Writes the cell to `path` whole, then renames it into place: a killed
    /// bake leaves no torn file. Errors name the file.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, self.encode())
            .and_then(|_| std::fs::rename(&tmp, path))
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// A cell from its file's bytes; `path` names the file in errors.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Cell, String> {
        let bad = |what: &str| format!("{}: {what}", path.display());
        if bytes.len() != FILE_BYTES {
            return Err(bad(&format!(
                "{} bytes, a cell file has {FILE_BYTES}",
                bytes.len()
            )));
        }
        if bytes[..4] != MAGIC {
            return Err(bad("not a himal probe cell (magic)"));
        }
        let (body, tail) = bytes.split_at(FILE_BYTES - 4);
        if crc32fast::hash(body) != u32::from_le_bytes(tail.try_into().expect("4 bytes")) {
            return Err(bad("checksum mismatch (damaged or partly written)"));
        }
        let word =
            |k: usize| u32::from_le_bytes(bytes[4 + 4 * k..8 + 4 * k].try_into().expect("4 bytes"));
        if word(0) != VERSION {
            return Err(bad(&format!(
                "version {}, this build reads {VERSION}",
                word(0)
            )));
        }
        if word(4) != CELL_PROBES as u32 || word(6) != TRANSFER_FLOATS as u32 {
            return Err(bad("unexpected probe layout"));
        }
        let mip = word(1);
        if mip as usize >= MIPS {
            return Err(bad(&format!("mip {mip} (at most {})", MIPS - 1)));
        }
        let key = CellKey {
            mip: mip as u8,
            x: word(2) as i32,
            z: word(3) as i32,
        };
        let mut heights = [0.0; PROBES_PER_CELL];
        let h0 = HEADER_BYTES;
        for (k, h) in heights.iter_mut().enumerate() {
            *h = f32::from_le_bytes(
                bytes[h0 + 4 * k..h0 + 4 * k + 4]
                    .try_into()
                    .expect("4 bytes"),
            );
        }
        let t0 = h0 + 4 * PROBES_PER_CELL;
        let probes = bytes[t0..FILE_BYTES - 4]
            .chunks_exact(TRANSFER_FLOATS * 2)
            .map(|p| {
                let mut t = Transfer::default();
                for (v, b) in t.m.iter_mut().zip(p.chunks_exact(2)) {
                    *v = f16::from_le_bytes([b[0], b[1]]).to_f32();
                }
                t
            })
            .collect();
        Ok(Cell {
            key,
            heights,
            probes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(key: CellKey, seed: f32) -> Cell {
        let mut c = Cell {
            key,
            heights: [0.0; PROBES_PER_CELL],
            probes: vec![Transfer::default(); PROBES_PER_CELL],
        };
        for (k, p) in c.probes.iter_mut().enumerate() {
            c.heights[k] = seed + k as f32;
            for (n, v) in p.m.iter_mut().enumerate() {
                *v = seed * 0.01 + (k * 48 + n) as f32 * 1e-4;
            }
        }
        c
    }

    #[test]
    fn file_round_trips_within_f16_and_is_under_the_talks_8_kb() {
        let c = cell(
            CellKey {
                mip: 2,
                x: 7,
                z: -3,
            },
            1.0,
        );
        let bytes = c.encode();
        assert_eq!(bytes.len(), FILE_BYTES);
        const { assert!(FILE_BYTES <= 8 * 1024) };
        let back = Cell::decode(&bytes, Path::new("c.hmlp")).unwrap();
        assert_eq!(back.key, c.key);
        assert_eq!(back.heights, c.heights);
        for (a, b) in back.probes.iter().zip(&c.probes) {
            for (x, y) in a.m.iter().zip(b.m) {
                // f16 keeps 11 significant bits: relative error below 2^-11.
                assert!((x - y).abs() <= y.abs() * 4.9e-4 + 1e-7, "{x} vs {y}");
            }
        }
    }

    #[test]
    fn damaged_files_are_refused_with_the_path() {
        let mut bytes = cell(CellKey { mip: 0, x: 1, z: 2 }, 2.0).encode();
        bytes[100] ^= 1;
        let e = Cell::decode(&bytes, Path::new("x/m0_1_2.hmlp")).unwrap_err();
        assert!(e.contains("x/m0_1_2.hmlp") && e.contains("checksum"), "{e}");
        let e = Cell::decode(&bytes[..10], Path::new("y.hmlp")).unwrap_err();
        assert!(e.contains("y.hmlp") && e.contains("bytes"), "{e}");
    }

    #[test]
    fn a_mip_probe_is_the_mean_of_the_2x2_child_probes_it_covers() {
        let parent = CellKey { mip: 1, x: 3, z: 4 };
        let kids = parent.children();
        let cells: Vec<Cell> = kids
            .iter()
            .enumerate()
            .map(|(n, k)| cell(*k, n as f32 * 10.0))
            .collect();
        let down = Cell::downsample(
            parent,
            [
                Some(&cells[0]),
                Some(&cells[1]),
                Some(&cells[2]),
                Some(&cells[3]),
            ],
        )
        .unwrap();
        // Parent probe (5, 6): child 3 (x >= 4, z >= 4), child probes (2..4, 4..6).
        let mean = (cells[3].heights[4 * 8 + 2]
            + cells[3].heights[4 * 8 + 3]
            + cells[3].heights[5 * 8 + 2]
            + cells[3].heights[5 * 8 + 3])
            / 4.0;
        assert!((down.heights[6 * 8 + 5] - mean).abs() < 1e-4);
        // Probe positions nest: the parent probe is at the centre of its four children.
        let o = Vec2::new(-5120.0, -5120.0);
        let p = Cell::probe_xz(parent, o, 5, 6);
        let c = (Cell::probe_xz(kids[3], o, 2, 4) + Cell::probe_xz(kids[3], o, 3, 5)) * 0.5;
        assert!(p.abs_diff_eq(c, 1e-3), "{p} vs {c}");
        assert!(Cell::downsample(parent, [None; 4]).is_none());
    }
}
