//! A row's pre-registered tuning grid: its dimensions (dotted paths into the algorithm's config,
//! `"m"` or `"baseline"`) and its points, the Cartesian product of the dimensions' values.

use ilopt::algo::AlgorithmConfig;
use ilopt::baseline::Baseline;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// One dimension of a pre-registered tuning grid: a dotted path into the algorithm's config
/// (its JSON form, e.g. `"alpha"`, `"step.eta"`, `"schedule"`, `"inner.rule.alpha"`), `"m"`
/// (trajectories per gradient, via [`ilopt::batched::Batched`]) or `"baseline"` (a
/// [`Baseline`] in its JSON form, e.g. `{ kind = "leave-one-out" }`), and the values tried, in
/// order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridDim {
    /// The path.
    pub path: String,
    /// The values (grid order).
    pub values: Vec<serde_json::Value>,
}

/// One point of a row's grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridPoint {
    /// Position in grid order.
    pub index: usize,
    /// The value of each dimension (path, value), in the grid's dimension order.
    pub values: Vec<(String, Value)>,
    /// The algorithm config at this point.
    pub config: AlgorithmConfig,
    /// Trajectories per gradient.
    pub m: usize,
    /// The oracle's baseline ([`Baseline::None`]: eq. 3.15 as it is).
    #[serde(default)]
    pub baseline: Baseline,
}

impl GridPoint {
    /// `path=value, …` (or `as configured` for a row without a grid).
    pub fn describe(&self) -> String {
        if self.values.is_empty() {
            return match &self.baseline {
                Baseline::None => format!("as configured, m={}", self.m),
                b => format!(
                    "as configured, m={}, baseline={}",
                    self.m,
                    compact(&serde_json::to_value(b).unwrap_or_default())
                ),
            };
        }
        let mut parts: Vec<String> = self
            .values
            .iter()
            .map(|(p, v)| format!("{p}={}", compact(v)))
            .collect();
        if self.baseline != Baseline::None && !self.values.iter().any(|(p, _)| p == "baseline") {
            parts.push(format!(
                "baseline={}",
                compact(&serde_json::to_value(&self.baseline).unwrap_or_default())
            ));
        }
        parts.join(", ")
    }
}

/// A JSON value in one line without quotes around plain strings.
pub fn compact(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Object(o) => {
            let parts: Vec<String> = o
                .iter()
                .map(|(k, v)| format!("{k}={}", compact(v)))
                .collect();
            format!("{{{}}}", parts.join(" "))
        }
        other => other.to_string(),
    }
}

fn set_path(root: &mut Value, path: &str, value: Value) -> Result<(), String> {
    let mut cur = root;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, p) in parts.iter().enumerate() {
        let obj = cur
            .as_object_mut()
            .ok_or_else(|| format!("`{path}`: `{p}` is not inside a table"))?;
        if i + 1 == parts.len() {
            if !obj.contains_key(*p) {
                return Err(format!(
                    "`{path}`: the config has no field `{p}` to tune (a grid sets existing fields)"
                ));
            }
            obj.insert((*p).to_string(), value);
            return Ok(());
        }
        cur = obj
            .get_mut(*p)
            .ok_or_else(|| format!("`{path}`: the config has no field `{p}`"))?;
    }
    Err(format!("`{path}`: empty path"))
}

/// The points of the grid `dims` around `config` with `m` trajectories per gradient and
/// `baseline` (absent: none), in grid order (the first dimension varying slowest); without dimensions, one point: the config as
/// given.
///
/// # Errors
/// A message naming the dimension when a path does not exist, a dimension is empty or repeated,
/// `m` is not a positive integer, a baseline is not one, or a point is not a valid config.
pub fn points(
    config: &AlgorithmConfig,
    m: Option<usize>,
    baseline: Option<&Baseline>,
    dims: &[GridDim],
) -> Result<Vec<GridPoint>, String> {
    let base = serde_json::to_value(config).map_err(|e| e.to_string())?;
    let base_m = m.unwrap_or(1);
    let mut seen = std::collections::BTreeSet::new();
    for d in dims {
        if d.values.is_empty() {
            return Err(format!("dimension `{}` has no values", d.path));
        }
        if !seen.insert(d.path.clone()) {
            return Err(format!("dimension `{}` repeated", d.path));
        }
    }
    let total: usize = dims.iter().map(|d| d.values.len()).product();
    let mut out = Vec::with_capacity(total);
    for index in 0..total {
        // Mixed radix, the last dimension varying fastest.
        let mut rest = index;
        let mut picks = vec![0usize; dims.len()];
        for (k, d) in dims.iter().enumerate().rev() {
            picks[k] = rest % d.values.len();
            rest /= d.values.len();
        }
        let mut json = base.clone();
        let mut m = base_m;
        let mut baseline = baseline.cloned().unwrap_or_default();
        let mut values = Vec::new();
        for (d, &i) in dims.iter().zip(&picks) {
            let v = d.values[i].clone();
            if d.path == "m" {
                m = v
                    .as_u64()
                    .filter(|&x| x >= 1)
                    .ok_or_else(|| format!("`m` values must be integers ≥ 1, got {v}"))?
                    as usize;
            } else if d.path == "baseline" {
                baseline = serde_json::from_value(v.clone())
                    .map_err(|e| format!("`baseline` value {v} is not a baseline: {e}"))?;
            } else {
                set_path(&mut json, &d.path, v.clone())?;
            }
            values.push((d.path.clone(), v));
        }
        let config: AlgorithmConfig = serde_json::from_value(json)
            .map_err(|e| format!("grid point {index} is not a valid config: {e}"))?;
        out.push(GridPoint {
            index,
            values,
            config,
            m,
            baseline,
        });
    }
    Ok(out)
}
