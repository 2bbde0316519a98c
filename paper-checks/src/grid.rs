//! A row's pre-registered tuning grid: its dimensions (dotted paths into the algorithm's config,
//! `"m"` or `"baseline"`) and its points, the Cartesian product of the dimensions' values.

use ilopt::algo::AlgorithmConfig;
use ilopt::baseline::Baseline;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// One dimension of a pre-registered tuning grid: a dotted path into the algorithm's config
/// (its JSON form, e.g. `"alpha"`, `"step.eta"`, `"schedule"`, `"inner.rule.alpha"`), `"m"`
/// (trajectories per gradient, via [`ilopt::batched::Batched`]) or `"baseline"` (a
/// [`Baseline`] in its JSON form, e.g. `{ kind = "leave-one-out" }`), and the values tried:
///
/// * `values`: a list, in order (a categorical dimension: its ends are not edges to extend);
/// * `from`, `to`: a **log dimension**, every value of the half-decade series
///   …, 10⁻³, 3·10⁻³, 10⁻², … ([`series_value`]) from `from` to `to` inclusive, or with
///   `per_decade = 1` every power of ten. Its ends are numeric edges: a pick on one grows the
///   range by the next value beyond it ([`GridDim::extended`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridDim {
    /// The path.
    pub path: String,
    /// The values (grid order) of a categorical dimension.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<serde_json::Value>,
    /// The smallest value of a log dimension (a member of the half-decade series).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<f64>,
    /// The largest value of a log dimension (a member of the half-decade series, ≥ `from`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
    /// Values per decade of a log dimension: 2 (the half-decade series, the default) or 1
    /// (powers of ten; `from` and `to` must then be powers of ten).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub per_decade: Option<u32>,
}

/// The `k`-th value of the half-decade series: 10^(k/2) for even k, 3·10^((k−1)/2) for odd k
/// (…, 1, 3, 10, 30, …), parsed from its decimal text so that it prints as written.
pub fn series_value(k: i32) -> f64 {
    let mantissa = if k.rem_euclid(2) == 0 { 1 } else { 3 };
    format!("{mantissa}e{}", k.div_euclid(2))
        .parse()
        .unwrap_or(f64::NAN)
}

/// The index `k` with [`series_value`]`(k) == v`, if `v` is a member of the series.
pub fn series_index(v: f64) -> Option<i32> {
    if !(v.is_finite() && v > 0.0) {
        return None;
    }
    let e = v.log10().floor() as i32;
    (2 * e - 2..=2 * e + 3).find(|&k| series_value(k) == v)
}

impl GridDim {
    /// A categorical dimension with these values.
    pub fn list(path: &str, values: Vec<Value>) -> Self {
        GridDim {
            path: path.into(),
            values,
            from: None,
            to: None,
            per_decade: None,
        }
    }

    /// A log dimension over the half-decade series from `from` to `to`.
    pub fn log(path: &str, from: f64, to: f64) -> Self {
        GridDim {
            path: path.into(),
            values: Vec::new(),
            from: Some(from),
            to: Some(to),
            per_decade: None,
        }
    }

    /// The series indices of a log dimension's ends, `None` for a categorical one.
    ///
    /// # Errors
    /// A message naming the dimension when it has both or neither of `values` and
    /// `from`/`to`, an end outside the series, or `from > to`.
    pub fn log_range(&self) -> Result<Option<(i32, i32)>, String> {
        match (self.from, self.to) {
            (None, None) => {
                if self.per_decade.is_some() {
                    Err(format!(
                        "dimension `{}`: `per_decade` applies to a log dimension (`from`/`to`)",
                        self.path
                    ))
                } else if self.values.is_empty() {
                    Err(format!("dimension `{}` has no values", self.path))
                } else {
                    Ok(None)
                }
            }
            (Some(from), Some(to)) => {
                if !self.values.is_empty() {
                    return Err(format!(
                        "dimension `{}`: give either `values` or `from`/`to`, not both",
                        self.path
                    ));
                }
                let index = |v: f64, name: &str| {
                    series_index(v).ok_or_else(|| {
                        format!(
                            "dimension `{}`: `{name}` = {v} is not in the half-decade series                              (1, 3, 10, 30, … times a power of ten)",
                            self.path
                        )
                    })
                };
                let (a, b) = (index(from, "from")?, index(to, "to")?);
                match self.per_decade {
                    None | Some(2) => {}
                    Some(1) => {
                        if a % 2 != 0 || b % 2 != 0 {
                            return Err(format!(
                                "dimension `{}`: with `per_decade = 1`, `from` and `to` must be \
                                 powers of ten",
                                self.path
                            ));
                        }
                    }
                    Some(k) => {
                        return Err(format!(
                            "dimension `{}`: `per_decade` = {k}; it must be 1 or 2",
                            self.path
                        ));
                    }
                }
                if a > b {
                    return Err(format!(
                        "dimension `{}`: `from` = {from} is above `to` = {to}",
                        self.path
                    ));
                }
                Ok(Some((a, b)))
            }
            _ => Err(format!(
                "dimension `{}`: a log dimension needs both `from` and `to`",
                self.path
            )),
        }
    }

    /// The values tried, in order.
    ///
    /// # Errors
    /// As [`GridDim::log_range`].
    pub fn resolved(&self) -> Result<Vec<Value>, String> {
        Ok(match self.log_range()? {
            None => self.values.clone(),
            Some((a, b)) => (a..=b)
                .step_by(self.stride() as usize)
                .map(|k| Value::from(series_value(k)))
                .collect(),
        })
    }

    /// The step in series indices between neighbouring values: 1 (half-decade) or 2.
    fn stride(&self) -> i32 {
        if self.per_decade == Some(1) { 2 } else { 1 }
    }

    /// Whether this is a log dimension (its ends are numeric edges).
    pub fn is_log(&self) -> bool {
        self.from.is_some() && self.to.is_some()
    }

    /// The log dimension grown by the next value of the series beyond its lower end (`upward`
    /// false) or its upper end (`upward` true); `None` for a categorical dimension.
    pub fn extended(&self, upward: bool) -> Option<GridDim> {
        let (a, b) = self.log_range().ok()??;
        let mut d = self.clone();
        if upward {
            d.to = Some(series_value(b + self.stride()));
        } else {
            d.from = Some(series_value(a - self.stride()));
        }
        Some(d)
    }
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
    /// Which sub-grid of the row the point belongs to (0 for a single product grid).
    #[serde(default)]
    pub subgrid: usize,
    /// The paths of its sub-grid's log dimensions, in order (the first is the point's step).
    #[serde(default)]
    pub log_dims: Vec<String>,
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

/// The points of a row's grid around `config` with `m` trajectories per gradient and
/// `baseline` (absent: none), in grid order: the union of the sub-grids' points, each sub-grid
/// the Cartesian product of its dimensions (the first varying slowest, values set in dimension
/// order, so that a later path may set a field inside an earlier one's value); without any
/// dimension, one point: the config as given.
///
/// # Errors
/// A message naming the dimension when a path does not exist, a dimension is empty, malformed
/// or repeated within its sub-grid, `m` is not a positive integer, a baseline is not one, or a
/// point is not a valid config.
pub fn points(
    config: &AlgorithmConfig,
    m: Option<usize>,
    baseline: Option<&Baseline>,
    subgrids: &[Vec<GridDim>],
) -> Result<Vec<GridPoint>, String> {
    if subgrids.is_empty() {
        return product(config, m, baseline, &[], 0, 0);
    }
    let mut out = Vec::new();
    for (g, dims) in subgrids.iter().enumerate() {
        let start = out.len();
        out.extend(product(config, m, baseline, dims, g, start)?);
    }
    Ok(out)
}

/// The product of `dims` (sub-grid `subgrid`), indexed from `start`.
fn product(
    config: &AlgorithmConfig,
    m: Option<usize>,
    baseline: Option<&Baseline>,
    dims: &[GridDim],
    subgrid: usize,
    start: usize,
) -> Result<Vec<GridPoint>, String> {
    let base = serde_json::to_value(config).map_err(|e| e.to_string())?;
    let base_m = m.unwrap_or(1);
    let mut seen = std::collections::BTreeSet::new();
    let mut values_of = Vec::with_capacity(dims.len());
    for d in dims {
        values_of.push(d.resolved()?);
        if !seen.insert(d.path.clone()) {
            return Err(format!("dimension `{}` repeated", d.path));
        }
    }
    let log_dims: Vec<String> = dims
        .iter()
        .filter(|d| d.is_log())
        .map(|d| d.path.clone())
        .collect();
    let total: usize = values_of.iter().map(Vec::len).product();
    let mut out = Vec::with_capacity(total);
    for offset in 0..total {
        let index = start + offset;
        // Mixed radix, the last dimension varying fastest.
        let mut rest = offset;
        let mut picks = vec![0usize; dims.len()];
        for (k, vs) in values_of.iter().enumerate().rev() {
            picks[k] = rest % vs.len();
            rest /= vs.len();
        }
        let mut json = base.clone();
        let mut m = base_m;
        let mut baseline = baseline.cloned().unwrap_or_default();
        let mut values = Vec::new();
        for ((d, vs), &i) in dims.iter().zip(&values_of).zip(&picks) {
            let v = vs[i].clone();
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
            subgrid,
            log_dims: log_dims.clone(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_half_decade_series_round_trips_and_prints_as_written() {
        assert_eq!(series_value(0), 1.0);
        assert_eq!(series_value(1), 3.0);
        assert_eq!(series_value(-1), 0.3);
        assert_eq!(series_value(-16), 1e-8);
        assert_eq!(series_value(-15), 3e-8);
        for k in -30..30 {
            assert_eq!(series_index(series_value(k)), Some(k), "k = {k}");
        }
        for v in [2e-3, 0.0, -1.0, f64::NAN, f64::INFINITY, 3.0000001] {
            assert_eq!(series_index(v), None, "{v}");
        }
        assert_eq!(Value::from(series_value(-15)).to_string(), "3e-8");
    }

    #[test]
    fn a_log_dimension_lists_its_series_and_extends_beyond_either_end() {
        let d = GridDim::log("step.eta", 1e-4, 1e-2);
        let vs: Vec<f64> = d
            .resolved()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(vs, vec![1e-4, 3e-4, 1e-3, 3e-3, 1e-2]);
        assert_eq!(d.extended(true).unwrap().to, Some(3e-2));
        assert_eq!(d.extended(false).unwrap().from, Some(3e-5));
        assert!(
            GridDim::list("m", vec![1.into(), 16.into()])
                .extended(true)
                .is_none()
        );
        let decades = GridDim {
            per_decade: Some(1),
            ..GridDim::log("alpha", 1e-4, 1e-2)
        };
        let vs: Vec<f64> = decades
            .resolved()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(vs, vec![1e-4, 1e-3, 1e-2]);
        assert_eq!(decades.extended(true).unwrap().to, Some(1e-1));
        assert_eq!(decades.extended(false).unwrap().from, Some(1e-5));
        let odd = GridDim {
            per_decade: Some(1),
            ..GridDim::log("alpha", 3e-4, 1e-2)
        };
        assert!(odd.resolved().unwrap_err().contains("powers of ten"));
        let three = GridDim {
            per_decade: Some(3),
            ..GridDim::log("alpha", 1e-4, 1e-2)
        };
        assert!(three.resolved().unwrap_err().contains("1 or 2"));
        for (bad, what) in [
            (
                GridDim::log("x", 2e-3, 1e-2),
                "not in the half-decade series",
            ),
            (GridDim::log("x", 1e-2, 1e-3), "above `to`"),
            (GridDim::list("x", vec![]), "no values"),
            (
                GridDim {
                    values: vec![1.into()],
                    ..GridDim::log("x", 1e-3, 1e-2)
                },
                "not both",
            ),
            (
                GridDim {
                    to: None,
                    ..GridDim::log("x", 1e-3, 1e-2)
                },
                "needs both `from` and `to`",
            ),
        ] {
            let e = bad.resolved().unwrap_err();
            assert!(e.contains(what) && e.contains("`x`"), "{e}");
        }
    }

    #[test]
    fn sub_grids_are_united_in_order_and_later_paths_set_fields_of_earlier_values() {
        let config: AlgorithmConfig = serde_json::from_value(serde_json::json!({
            "algorithm": "storm", "form": "causal", "correction": "unweighted",
            "schedule": {"kind": "constant", "eta": 1e-3, "a": 0.5}
        }))
        .unwrap();
        let constant = vec![
            GridDim::log("schedule.eta", 1e-3, 3e-3),
            GridDim::list("schedule.a", vec![0.1.into(), 0.9.into()]),
        ];
        let adaptive = vec![
            GridDim::list(
                "schedule",
                vec![serde_json::json!({"kind": "adaptive", "k": 0.1, "w": 0.1, "c": 100})],
            ),
            GridDim::log("schedule.k", 1e-2, 1e-2),
        ];
        let pts = points(&config, None, None, &[constant, adaptive]).unwrap();
        assert_eq!(pts.len(), 5);
        assert_eq!(
            pts.iter().map(|p| p.index).collect::<Vec<_>>(),
            vec![0, 1, 2, 3, 4]
        );
        assert_eq!(pts[1].describe(), "schedule.eta=0.001, schedule.a=0.9");
        assert_eq!((pts[3].subgrid, pts[4].subgrid), (0, 1));
        let json = serde_json::to_value(&pts[4].config).unwrap();
        assert_eq!(json["schedule"]["kind"], "adaptive");
        let direct: AlgorithmConfig = serde_json::from_value(serde_json::json!({
            "algorithm": "storm", "form": "causal", "correction": "unweighted",
            "schedule": {"kind": "adaptive", "k": 0.01, "w": 0.1, "c": 100}
        }))
        .unwrap();
        assert_eq!(pts[4].config, direct);
        assert_eq!(pts[4].log_dims, vec!["schedule.k".to_string()]);
    }
}
