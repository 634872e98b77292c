//! V1's baked data: per tree (species, seed) the clusters' visibility
//! scores and each leaf level's card scale, cached on disk so a scene does
//! not rasterise 108 views per tree on every load (the rosewood takes about
//! a second). `himal bake --trees` fills the cache; scene loading reads it
//! and bakes what is missing (when a cache directory is set,
//! [`set_cache_dir`]).
//!
//! File `<dir>/trees/<species>-<seed>.himal-tree`, little-endian: magic
//! `HTRE`, version, the model's fingerprint (FNV-1a of its cards: a changed
//! generator invalidates the file), cluster count, `LEVELS` card scales,
//! one score per cluster. A bad or stale file is rebaked and rewritten.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use super::{LEVELS, Species, TreeModel, VisibilityTable, visibility};

const MAGIC: &[u8; 4] = b"HTRE";
const VERSION: u32 = 3;

static CACHE_DIR: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Where scene loading reads and writes baked trees (`None`: bake in memory each load).
pub fn set_cache_dir(dir: Option<PathBuf>) {
    if let Ok(mut d) = CACHE_DIR.lock() {
        *d = dir;
    }
}

/// The cache directory [`set_cache_dir`] set.
pub fn cache_dir() -> Option<PathBuf> {
    CACHE_DIR.lock().ok().and_then(|d| d.clone())
}

/// A tree's baked leaf LODs.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafLods {
    /// Visibility score per cluster ([`VisibilityTable::score`]).
    pub score: Vec<f32>,
    /// Scale of the kept clusters per level (1 for LOD0).
    pub card_scale: [f32; LEVELS],
}

impl LeafLods {
    /// The levels of `model` from its visibility `table`: per level the
    /// scale at which the kept clusters cover LOD0's pixels
    /// ([`visibility::compensation`]).
    pub fn new(model: &TreeModel, table: &VisibilityTable) -> Self {
        let mut lods = LeafLods {
            score: table.score.clone(),
            card_scale: [1.0; LEVELS],
        };
        for level in 1..LEVELS {
            let kept = lods.kept(model, level);
            lods.card_scale[level] = visibility::compensation(model, &kept);
        }
        lods
    }

    /// Cluster indices, most visible first (ties by index).
    pub fn ranking(&self) -> Vec<usize> {
        visibility::rank(&self.score)
    }

    /// The clusters level `level` keeps, in index order: the
    /// [`Species::keep`] fraction (at least one), the most visible of each
    /// of [`HEIGHT_BANDS`] bands of the crown in proportion to the band's
    /// clusters, so a far level keeps the crown's outline (a larch's long
    /// lower branches are the most visible from every view, and a global
    /// ranking would leave its top bare).
    pub fn kept(&self, model: &TreeModel, level: usize) -> Vec<usize> {
        let order = self.ranking();
        let keep = model.species.keep()[level.min(LEVELS - 1)];
        let n = ((keep * order.len() as f32).round() as usize).clamp(1, order.len().max(1));
        let band = height_bands(model);
        let mut in_band = [0usize; HEIGHT_BANDS];
        for &b in &band {
            in_band[b] += 1;
        }
        let total = band.len().max(1) as f32;
        let mut quota = in_band.map(|c| (c as f32 * n as f32 / total).round() as usize);
        let mut kept = Vec::with_capacity(n);
        for &c in &order {
            if kept.len() < n && band.get(c).is_some_and(|&b| quota[b] > 0) {
                quota[band[c]] -= 1;
                kept.push(c);
            }
        }
        // Rounding may leave places: the most visible of the rest fill them.
        for &c in &order {
            if kept.len() >= n {
                break;
            }
            if !kept.contains(&c) {
                kept.push(c);
            }
        }
        kept.sort_unstable();
        kept
    }
}

/// Height bands of the crown a level's clusters are spread over.
pub const HEIGHT_BANDS: usize = 6;

/// Each cluster's band: its centre's height between the lowest and the
/// highest cluster centre, in [`HEIGHT_BANDS`] equal steps.
pub fn height_bands(model: &TreeModel) -> Vec<usize> {
    let ys = model.clusters.iter().map(|c| c.centre.y);
    let lo = ys.clone().fold(f32::INFINITY, f32::min);
    let hi = ys.fold(f32::NEG_INFINITY, f32::max);
    let span = (hi - lo).max(1e-3);
    (model.clusters.iter())
        .map(|c| (((c.centre.y - lo) / span * HEIGHT_BANDS as f32) as usize).min(HEIGHT_BANDS - 1))
        .collect()
}

/// FNV-1a over the cards' centres, sizes and clusters.
pub fn fingerprint(model: &TreeModel) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for c in &model.cards {
        for v in c.centre.to_array() {
            eat(v.to_bits());
        }
        eat(c.size.to_bits());
        eat(c.cluster);
    }
    eat(model.clusters.len() as u32);
    h
}

/// The cache file of tree (`species`, `seed`) under `dir`.
pub fn cache_file(dir: &Path, species: Species, seed: u32) -> PathBuf {
    dir.join("trees")
        .join(format!("{}-{seed}.himal-tree", species.name()))
}

fn encode(model: &TreeModel, lods: &LeafLods) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + 4 * lods.score.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&fingerprint(model).to_le_bytes());
    out.extend_from_slice(&(lods.score.len() as u32).to_le_bytes());
    for v in lods.card_scale.iter().chain(&lods.score) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The file's levels, if it is whole and made for `model`.
fn decode(model: &TreeModel, bytes: &[u8]) -> Option<LeafLods> {
    let word = |at: usize| -> Option<[u8; 4]> { bytes.get(at..at + 4)?.try_into().ok() };
    if bytes.get(..4)? != MAGIC || u32::from_le_bytes(word(4)?) != VERSION {
        return None;
    }
    let print = u64::from_le_bytes(bytes.get(8..16)?.try_into().ok()?);
    let n = u32::from_le_bytes(word(16)?) as usize;
    if print != fingerprint(model)
        || n != model.clusters.len()
        || bytes.len() != 20 + 4 * (LEVELS + n)
    {
        return None;
    }
    let f = |i: usize| word(20 + 4 * i).map(f32::from_le_bytes);
    let card_scale = [f(0)?, f(1)?, f(2)?];
    let score = (0..n)
        .map(|i| f(LEVELS + i))
        .collect::<Option<Vec<f32>>>()?;
    let finite = card_scale.iter().chain(&score).all(|v| v.is_finite());
    finite.then_some(LeafLods { score, card_scale })
}

/// Bakes `model`'s leaf LODs (visibility table, card scales).
pub fn bake(model: &TreeModel) -> LeafLods {
    LeafLods::new(model, &visibility::table(model))
}

/// Reads tree (`model.species`, `seed`)'s levels from `dir`, or bakes and
/// writes them; `Ok(true)` when read from the cache.
pub fn load_or_bake_in(dir: &Path, model: &TreeModel, seed: u32) -> (LeafLods, bool) {
    let path = cache_file(dir, model.species, seed);
    if let Some(lods) = std::fs::read(&path).ok().and_then(|b| decode(model, &b)) {
        return (lods, true);
    }
    let lods = bake(model);
    let written = std::fs::create_dir_all(path.parent().unwrap_or(dir))
        .and_then(|_| std::fs::write(&path, encode(model, &lods)));
    if let Err(e) = written {
        log::warn!("tree cache {}: {e} (baked in memory)", path.display());
    }
    (lods, false)
}

/// The levels of `model` through the cache directory [`set_cache_dir`]
/// set, or baked in memory without one; once per process ([`Memo`]).
pub fn load_or_bake(model: &TreeModel, seed: u32) -> LeafLods {
    static MEMO: Memo<LeafLods> = Memo::new();
    let lods = MEMO.get_or(model, seed, || match cache_dir() {
        Some(dir) => load_or_bake_in(&dir, model, seed).0,
        None => bake(model),
    });
    (*lods).clone()
}

/// What a tree's baked data depends on: species, seed, the generated
/// model's fingerprint and the cache directory (a new directory still
/// gets its files written).
type MemoKey = (Species, u32, u64, Option<PathBuf>);

/// A tree's baked data kept for the process, so loading scenes again (the
/// tests, the viewer's reload) does not bake their trees again: a second
/// or two per tree without a cache. Bounded by the trees scenes name.
pub struct Memo<T>(OnceLock<Mutex<HashMap<MemoKey, Arc<T>>>>);

impl<T> Memo<T> {
    /// An empty memo (for a `static`).
    pub const fn new() -> Self {
        Memo(OnceLock::new())
    }

    /// The data of tree `model` (from `seed`), made by `make` on first use.
    /// Made outside the lock: two threads may both make it once.
    pub fn get_or(&self, model: &TreeModel, seed: u32, make: impl FnOnce() -> T) -> Arc<T> {
        let key = (model.species, seed, fingerprint(model), cache_dir());
        let map = self.0.get_or_init(Default::default);
        let lock = || map.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(v) = lock().get(&key) {
            return v.clone();
        }
        let made = Arc::new(make());
        lock().entry(key).or_insert(made).clone()
    }
}

impl<T> Default for Memo<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// The (species, seed) of every `tree` object in scene file text `text`
/// (unique, in file order), for `himal bake --trees`; unknown species are
/// skipped (loading the scene reports them).
pub fn trees_in(text: &str) -> Result<Vec<(Species, u32)>, String> {
    let value: toml::Value = toml::from_str(text).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    let objects = value.get("object").and_then(|o| o.as_array());
    for o in objects.into_iter().flatten() {
        if o.get("primitive").and_then(|p| p.as_str()) != Some("tree") {
            continue;
        }
        let species = o
            .get("species")
            .and_then(|s| s.as_str())
            .and_then(Species::parse);
        let seed = o.get("seed").and_then(|s| s.as_integer()).unwrap_or(0);
        if let (Some(species), Ok(seed)) = (species, u32::try_from(seed))
            && !out.contains(&(species, seed))
        {
            out.push((species, seed));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::generate;
    use super::*;

    #[test]
    fn cache_round_trips_and_rejects_other_trees() {
        let model = generate(Species::Larch, 2, 0.1);
        let lods = bake(&model);
        let bytes = encode(&model, &lods);
        assert_eq!(decode(&model, &bytes), Some(lods.clone()));
        assert_eq!(decode(&generate(Species::Larch, 3, 0.1), &bytes), None);
        assert_eq!(decode(&model, &bytes[..bytes.len() - 1]), None);
        let dir = std::env::temp_dir().join(format!("himal-tree-cache-{}", std::process::id()));
        let (a, read) = load_or_bake_in(&dir, &model, 2);
        assert!(!read && a == lods);
        let (b, read) = load_or_bake_in(&dir, &model, 2);
        assert!(read && b == lods);
        let _ = std::fs::remove_dir_all(&dir);
        let text =
            "[[object]]\nname = \"a\"\nprimitive = \"tree\"\nspecies = \"rosewood\"\nseed = 4\n";
        assert_eq!(trees_in(text), Ok(vec![(Species::Rosewood, 4)]));
    }
}
