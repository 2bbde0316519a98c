//! Spreading one profile over several processes or machines.
//!
//! The work of a profile is a set of *units*: one tuning run (row, grid point, tuning seed) or one
//! report run (row at its selected hyper-parameters, report seed), plus the Fig. 4.2 study and the
//! theorem table. Each unit has a key (a hash of everything that determines it, the code version
//! included). `paper-checks --shard K/N` computes the units whose key falls to shard K and
//! stores each in `runs/units/<key>.json`; the report runs need every row's tuning, so a shard
//! computes its report units once the tuning units of all shards are in the store (run each shard
//! twice, or the array twice: see docs/appendix.md). `paper-checks merge` then assembles the appendix
//! from the store without computing anything, and a plain run computes whatever is missing.
//! Every unit's result depends only on its key, so the merged data files are byte-identical to
//! a single run's.

use crate::error::Error;
use crate::storage::{to_json, write_atomic};
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Shard `index + 1` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 0-based index (`K − 1`).
    pub index: u64,
    /// Number of shards `N`.
    pub count: u64,
}

impl Shard {
    /// Parse `K/N` with 1 ≤ K ≤ N.
    ///
    /// # Errors
    /// A message naming what is wrong with `text`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| format!("`{text}`: expected K/N, e.g. 2/8"))?;
        let k: u64 = k
            .trim()
            .parse()
            .map_err(|_| format!("`{text}`: shard number K = `{k}` is not a positive integer"))?;
        let n: u64 = n
            .trim()
            .parse()
            .map_err(|_| format!("`{text}`: shard count N = `{n}` is not a positive integer"))?;
        if n == 0 || k == 0 || k > n {
            return Err(format!("`{text}`: need 1 ≤ K ≤ N"));
        }
        Ok(Shard {
            index: k - 1,
            count: n,
        })
    }

    /// Whether the unit with this key (16 hex digits) falls to this shard.
    pub fn owns(&self, key: &str) -> bool {
        u64::from_str_radix(key, 16).unwrap_or_else(|_| crate::stats::fnv1a(key)) % self.count
            == self.index
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index + 1, self.count)
    }
}

/// What a run does with units that are not in the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Compute every missing unit (a plain run); do not store units.
    All,
    /// Compute and store the missing units of this shard only.
    Shard(Shard),
    /// Compute nothing: assemble from the store (`paper-checks merge`).
    Merge,
}

/// A unit as stored: its key and its result.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
struct Stored<T> {
    key_hash: String,
    value: T,
}

/// The unit store `runs/units/` of an output directory.
pub struct Units {
    dir: PathBuf,
    mode: Mode,
    redo: bool,
    missing: AtomicUsize,
    computed: AtomicUsize,
}

impl Units {
    /// The store under `runs_dir`; with `redo`, the units this run computes are recomputed even
    /// when stored.
    pub fn new(runs_dir: &Path, mode: Mode, redo: bool) -> Self {
        Units {
            dir: runs_dir.join("units"),
            mode,
            redo,
            missing: AtomicUsize::new(0),
            computed: AtomicUsize::new(0),
        }
    }

    /// The run's mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The file of the unit `key`.
    pub fn file(&self, key: &str) -> PathBuf {
        self.dir.join(format!("{key}.json"))
    }

    /// The unit `key`: from the store if there, else computed by `f` if this run computes it
    /// (stored when sharded), else `None` (counted as missing).
    ///
    /// # Errors
    /// Errors of `f`, or I/O errors writing the store.
    pub fn get<T: Serialize + DeserializeOwned>(
        &self,
        key: &str,
        f: impl FnOnce() -> Result<T, Error>,
    ) -> Result<Option<T>, Error> {
        let file = self.file(key);
        let compute = match self.mode {
            Mode::All => true,
            Mode::Shard(s) => s.owns(key),
            Mode::Merge => false,
        };
        if !(self.redo && compute)
            && let Some(s) = std::fs::read_to_string(&file)
                .ok()
                .and_then(|t| serde_json::from_str::<Stored<T>>(&t).ok())
                .filter(|s| s.key_hash == key)
        {
            return Ok(Some(s.value));
        }
        if !compute {
            self.missing.fetch_add(1, Ordering::Relaxed);
            return Ok(None);
        }
        let value = f()?;
        self.computed.fetch_add(1, Ordering::Relaxed);
        if matches!(self.mode, Mode::Shard(_)) {
            std::fs::create_dir_all(&self.dir).map_err(|e| Error::io(&self.dir, e))?;
            let stored = Stored {
                key_hash: key.to_string(),
                value,
            };
            write_atomic(&file, &to_json("unit", &stored)?)?;
            return Ok(Some(stored.value));
        }
        Ok(Some(value))
    }

    /// Units asked for that this run neither found nor computed.
    pub fn missing(&self) -> usize {
        self.missing.load(Ordering::Relaxed)
    }

    /// Units this run computed.
    pub fn computed(&self) -> usize {
        self.computed.load(Ordering::Relaxed)
    }

    /// Remove the stored units with these keys (after their configuration was assembled).
    pub fn remove(&self, keys: &[String]) {
        for k in keys {
            let _ = std::fs::remove_file(self.file(k));
        }
    }
}

/// The key of unit `part` (e.g. `seed=3`) of the configuration with key `config_key`.
pub fn unit_key(config_key: &str, part: &str) -> String {
    format!(
        "{:016x}",
        crate::stats::fnv1a(&format!("{config_key}|{part}"))
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition_the_keys() {
        assert_eq!(Shard::parse("2/8"), Ok(Shard { index: 1, count: 8 }));
        for bad in ["0/3", "4/3", "3", "a/3", "1/0", "-1/3"] {
            let e = Shard::parse(bad).expect_err(bad);
            assert!(e.contains(bad), "{e}");
        }
        let shards: Vec<Shard> = (1..=3)
            .map(|k| Shard::parse(&format!("{k}/3")).expect("valid"))
            .collect();
        for i in 0..200 {
            let key = unit_key("config", &format!("seed={i}"));
            assert_eq!(shards.iter().filter(|s| s.owns(&key)).count(), 1, "{key}");
        }
    }
}
