//! What an integrator carries from one step to the next, as data: the state a
//! checkpoint saves and a resume restores ([`IntegratorState`]), with floats kept to the
//! bit ([`Bits`], [`Floats`]). It sits below the integrators so that they save and restore
//! themselves without knowing the checkpoint file, which belongs to the run layer
//! (`run::checkpoint`).

use std::collections::BTreeMap;

use base64::Engine as _;
use serde::{Deserialize, Serialize};

use crate::error::Error;

/// An `f64` stored as its bits (`"0x3ff0000000000000"`), so it reads back exactly,
/// NaN and infinities included.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bits(pub f64);

impl Serialize for Bits {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{:#018x}", self.0.to_bits()))
    }
}

impl<'de> Deserialize<'de> for Bits {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        u64::from_str_radix(s.trim_start_matches("0x"), 16)
            .map(|b| Bits(f64::from_bits(b)))
            .map_err(|_| serde::de::Error::custom(format!("`{s}` is not 0x + 16 hex digits")))
    }
}

/// A vector of `f64` stored as base64 of its little-endian bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Floats(pub Vec<f64>);

impl Serialize for Floats {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let bytes: Vec<u8> = self.0.iter().flat_map(|x| x.to_le_bytes()).collect();
        s.serialize_str(&base64::engine::general_purpose::STANDARD.encode(bytes))
    }
}

impl<'de> Deserialize<'de> for Floats {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(s.as_bytes())
            .map_err(|e| serde::de::Error::custom(format!("not base64: {e}")))?;
        if bytes.len() % 8 != 0 {
            return Err(serde::de::Error::custom(format!(
                "{} bytes is not a whole number of f64",
                bytes.len()
            )));
        }
        Ok(Floats(
            bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        ))
    }
}

/// What an integrator carries from one step to the next: `t`, `q`, `v`, impulses (the
/// warm start of the next friction solve), projections, contact statuses and any vector
/// a scheme carries from step to step (Schatzman–Paoli's `q_{k−1}`); gaps, Jacobians and
/// Delassus data are functions of `q` and are evaluated again.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorState {
    /// The scheme's name (a checkpoint resumes with the scheme that wrote it).
    pub scheme: String,
    /// Steps taken.
    pub step: usize,
    /// Time (s).
    pub time: Bits,
    /// Named vectors: `q`, `v`, `impulse`, `projection`, `impulse_rows`,
    /// `local_velocity`, `tangent_velocity`, `tangent_impulse`, and a scheme's own.
    pub vectors: BTreeMap<String, Floats>,
    /// Contact status codes (frictional scenes: 0 open, 1 stick, 2 slip, 3 closed
    /// without friction).
    pub status: Vec<u8>,
    /// The step `h` the saving integrator ran at (`None`: a scheme at a constant `h`, or
    /// a checkpoint from before issue 49); an integrator restored at another `h` starts
    /// its clock at the saved step and time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<Bits>,
    /// The step the saved impulse was made over, where it is not `dt` (a state saved
    /// after a change of step, before a step at the new one): the warm start of a
    /// frictional solve is scaled by the ratio of the steps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impulse_dt: Option<Bits>,
    /// The step and time at which `h` last changed (`None`: the start, `t = 0`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<(usize, Bits)>,
}

impl IntegratorState {
    /// The vector `name`, which must have `len` entries; the error names the checkpoint.
    pub fn vector(&self, name: &str, len: usize) -> Result<&[f64], Error> {
        match self.vectors.get(name) {
            Some(v) if v.0.len() == len => Ok(&v.0),
            Some(v) => Err(Error::invalid(
                &format!("checkpoint integrator.vectors.{name}"),
                format!("{} values", v.0.len()),
                &format!("the model has {len} (was the mesh or the scene changed?)"),
            )),
            None => Err(Error::invalid(
                &format!("checkpoint integrator.vectors.{name}"),
                "(missing)",
                "a checkpoint of this scheme holds it",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vector of the wrong length or a missing one is named with the model's count
    /// (what `resume` reports for a checkpoint whose digest matches but whose model
    /// changed; an edited checkpoint is refused by its digest first).
    #[test]
    fn vectors_are_checked_against_the_model() {
        let s = IntegratorState {
            scheme: "moreau-jean".into(),
            step: 3,
            time: Bits(3e-6),
            vectors: [("q".to_string(), Floats(vec![0.0]))].into_iter().collect(),
            status: Vec::new(),
            dt: None,
            impulse_dt: None,
            origin: None,
        };
        assert_eq!(s.vector("q", 1).unwrap(), &[0.0]);
        let e = s.vector("q", 51).unwrap_err().to_string();
        assert!(
            e.contains("vectors.q") && e.contains("the model has 51"),
            "{e}"
        );
        let e = s.vector("v", 51).unwrap_err().to_string();
        assert!(e.contains("vectors.v") && e.contains("missing"), "{e}");
    }
}
