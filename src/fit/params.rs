//! The parameters of a fit: `KEY[=LO..HI]`, any number a sweep can vary
//! under `[model]` (the twin: `model.params.*`, `model.*`) or `[sim]` (the
//! physics: `sim.*`, `sim.perturb.*`), checked against the scenario before
//! anything runs: the key leads to a number (or to a key the file leaves
//! at its default), the range is a non-empty interval, and the scenario
//! still validates at both of its ends.

use crate::error::Error;
use crate::scenario::keypath::{self, Found, KeyPath, Segment};
use crate::scenario::Variant;
use crate::validate::Prepared;
use std::collections::BTreeMap;
use toml::de::DeTable;

/// Which run a key moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Moves {
    /// `model.*`: the ideal run (the twin).
    Model,
    /// `sim.*`: the physics run.
    Sim,
}

/// One parameter to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// The key path as written.
    pub key: String,
    /// Its range.
    pub lo: f64,
    /// Its range's upper end.
    pub hi: f64,
    /// Its value in the scenario (written or default), if known.
    pub nominal: Option<f64>,
    /// Which run it moves.
    pub moves: Moves,
}

/// `--param` as written: `KEY` or `KEY=LO..HI`.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamArg {
    /// The key.
    pub key: String,
    /// The range, when given.
    pub range: Option<(f64, f64)>,
}

const OPT: &str = "--param";

fn bad(arg: &str, m: impl std::fmt::Display) -> Error {
    Error::input(OPT, format!("`{arg}`: {m}"))
}

impl ParamArg {
    /// Parse `KEY` or `KEY=LO..HI`.
    pub fn parse(arg: &str) -> Result<ParamArg, Error> {
        let (key, range) = match arg.split_once('=') {
            None => (arg.trim(), None),
            Some((k, r)) => (k.trim(), Some(r.trim())),
        };
        KeyPath::parse(key).map_err(|m| bad(arg, m))?;
        let range = match range {
            None => None,
            Some(r) => {
                let Some((lo, hi)) = r.split_once("..") else {
                    return Err(bad(
                        arg,
                        "a range is written LO..HI (e.g. `sim.friction=0.3..1.2`)",
                    ));
                };
                let num = |s: &str, end: &str| -> Result<f64, Error> {
                    let s = s.trim();
                    match s.parse::<f64>() {
                        Ok(x) if x.is_finite() => Ok(x),
                        _ => Err(bad(
                            arg,
                            format!(
                                "the range's {end} `{s}` is not a finite number (write LO..HI)"
                            ),
                        )),
                    }
                };
                let (lo, hi) = (num(lo, "lower end")?, num(hi, "upper end")?);
                if lo == hi {
                    return Err(bad(
                        arg,
                        format!(
                            "an empty range ({} to itself): give LO < HI, or leave the key out to keep it at its value",
                            crate::numfmt::shortest(lo)
                        ),
                    ));
                }
                if lo > hi {
                    return Err(bad(
                        arg,
                        format!(
                            "an inverted range: write the lower end first, `{key}={}..{}`",
                            crate::numfmt::shortest(hi),
                            crate::numfmt::shortest(lo)
                        ),
                    ));
                }
                Some((lo, hi))
            }
        };
        Ok(ParamArg {
            key: key.to_string(),
            range,
        })
    }
}

/// The value at `path` (after its root) in a configuration serialized as JSON.
fn json_at(v: &serde_json::Value, path: &[Segment]) -> Option<f64> {
    let mut v = v;
    for s in path {
        v = match s {
            Segment::Key(k) => v.get(k)?,
            Segment::Index(i) => v.get(*i)?,
        };
    }
    v.as_f64()
}

/// A sweep-style variant setting `params`.
pub fn variant(params: BTreeMap<String, f64>) -> Variant {
    Variant {
        index: 0,
        seed: 0,
        mass_scale: 1.0,
        sigma_rate: None,
        params,
    }
}

/// The message of an error without the file and line it names (the
/// scenario's line holds the nominal value, not the one tried).
pub fn bare(e: &Error) -> String {
    match e {
        Error::Input { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// Check the `--param` arguments against a prepared scenario.
pub fn resolve(prep: &Prepared, args: &[ParamArg]) -> Result<Vec<Param>, Error> {
    let sc = &prep.scenario;
    let root = DeTable::parse(sc.text()).map_err(|e| Error::input(&sc.path, e.to_string()))?;
    let root = root.get_ref();
    let model_json = serde_json::to_value(&sc.model).unwrap_or_default();
    let sim_json = serde_json::to_value(&sc.sim).unwrap_or_default();
    let mut out: Vec<Param> = Vec::new();
    for a in args {
        let arg = match a.range {
            Some((lo, hi)) => format!(
                "{}={}..{}",
                a.key,
                crate::numfmt::shortest(lo),
                crate::numfmt::shortest(hi)
            ),
            None => a.key.clone(),
        };
        let kp = KeyPath::parse(&a.key).map_err(|m| bad(&arg, m))?;
        let kp_text = kp.to_string();
        if out.iter().any(|p| p.key == kp_text) {
            return Err(bad(&arg, "given twice"));
        }
        let moves = match kp.root() {
            "model" => Moves::Model,
            "sim" => Moves::Sim,
            other => {
                return Err(bad(
                    &arg,
                    format!(
                        "`{other}` keys cannot be fitted: a fit varies the twin (`model.*`, `model.params.*`: the ideal run) or the physics (`sim.*`, `sim.perturb.*`: the physics run)"
                    ),
                ))
            }
        };
        match keypath::find(root, &kp) {
            Found::Number { .. } => {}
            Found::NotNumber(t) => {
                return Err(bad(
                    &arg,
                    format!("`{kp}` is {t}, not a number: only numbers are fitted"),
                ))
            }
            Found::Unreachable(why) => {
                return Err(bad(
                    &arg,
                    format!("no such number in {}: {why}", sc.path.display()),
                ))
            }
            Found::Absent => {
                // A declared model's parameter must be one its expressions use.
                if kp.0.len() == 3 && kp.prefix(2) == "model.params" {
                    let names: Vec<String> = model_json
                        .get("params")
                        .and_then(|p| p.as_object())
                        .map(|o| o.keys().cloned().collect())
                        .unwrap_or_default();
                    return Err(bad(
                        &arg,
                        format!(
                            "the model has no parameter `{}` (its `[model.params]`: {})",
                            kp.0[2].key_text(),
                            if names.is_empty() {
                                "none".into()
                            } else {
                                names.join(", ")
                            }
                        ),
                    ));
                }
            }
        }
        let nominal = match moves {
            Moves::Model => json_at(&model_json, &kp.0[1..]),
            Moves::Sim => json_at(&sim_json, &kp.0[1..]),
        };
        let (lo, hi) = match (a.range, nominal) {
            (Some(r), _) => r,
            (None, Some(v)) if v != 0.0 => {
                let (x, y) = (0.5 * v, 2.0 * v);
                (x.min(y), x.max(y))
            }
            (None, _) => {
                return Err(bad(
                    &arg,
                    format!(
                        "its value is {}: give its range, `{kp}=LO..HI`",
                        nominal.map_or("not known".into(), |_| "0".to_string())
                    ),
                ))
            }
        };
        // The scenario must still validate at both ends (and in between:
        // an integer key refuses a fraction).
        for x in [lo, hi, lo + 0.37 * (hi - lo)] {
            let mut p = BTreeMap::new();
            p.insert(kp_text.clone(), x);
            if let Err(e) = prep.variant(&variant(p)) {
                return Err(bad(
                    &arg,
                    format!(
                        "with `{kp}` = {}, the scenario is refused: {}",
                        crate::numfmt::readable(x),
                        bare(&e)
                    ),
                ));
            }
        }
        out.push(Param {
            key: kp_text,
            lo,
            hi,
            nominal,
            moves,
        });
    }
    Ok(out)
}

trait KeyText {
    fn key_text(&self) -> String;
}

impl KeyText for Segment {
    fn key_text(&self) -> String {
        match self {
            Segment::Key(k) => k.clone(),
            Segment::Index(i) => format!("[{i}]"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_bad_ones_say_why() {
        assert_eq!(
            ParamArg::parse("sim.friction=0.2..1.5").unwrap(),
            ParamArg {
                key: "sim.friction".into(),
                range: Some((0.2, 1.5))
            }
        );
        assert_eq!(ParamArg::parse("model.params.eta").unwrap().range, None);
        let e = |a: &str| ParamArg::parse(a).unwrap_err().to_string();
        assert!(e("sim.friction=1..1").contains("an empty range"));
        assert!(e("sim.friction=2..1")
            .contains("inverted range: write the lower end first, `sim.friction=1..2`"));
        assert!(e("sim.friction=1").contains("LO..HI"));
        assert!(e("sim.friction=a..1").contains("lower end `a`"));
        assert!(e("sim..friction").contains("not a key path"));
        assert!(e("sim.friction=..").starts_with("--param: `sim.friction=..`"));
    }
}
