//! The fixed-step engine's stored form (checkpoints, `Simulation::state`): a map of its
//! named fields, in declaration order, as a derived serde implementation writes it.
//!
//! Only the law, the bond and the generator depend on the engine's type parameters. The
//! code for every other field is here, compiled once, instead of once for each of the
//! engine's types (a derived implementation compiles its visitor per type); the three
//! typed fields are written through `erased_serde` and read by the caller's [`Typed`]
//! functions.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

use super::integrator::Integrator;
use crate::physics::{Formation, Plate};

/// The stored fields, in the engine's declaration order (the order of the map).
pub(super) const FIELDS: [&str; 21] = [
    "law",
    "bond",
    "flip",
    "formation",
    "plate",
    "integrator",
    "rng",
    "dt",
    "relax",
    "unstretched",
    "strong_off_threshold",
    "steps",
    "plate_x",
    "plate_v",
    "q",
    "x",
    "pending_dx",
    "pending_relax",
    "attached",
    "ruptures",
    "formations",
];

/// The typed fields, in the order of [`Typed`]'s three functions.
const TYPED: [&str; 3] = ["law", "bond", "rng"];

/// An engine's fields as written, the typed ones type-erased.
#[derive(Serialize)]
#[serde(rename = "FixedEngine")]
pub(super) struct Written<'a> {
    pub law: &'a dyn erased_serde::Serialize,
    pub bond: &'a dyn erased_serde::Serialize,
    pub flip: PhantomData<()>,
    pub formation: &'a Formation,
    pub plate: &'a Plate,
    pub integrator: &'a Integrator,
    pub rng: &'a dyn erased_serde::Serialize,
    pub dt: f64,
    pub relax: f64,
    pub unstretched: bool,
    pub strong_off_threshold: f64,
    pub steps: u64,
    pub plate_x: f64,
    pub plate_v: f64,
    pub q: &'a [u8],
    pub x: &'a [f64],
    pub pending_dx: f64,
    pub pending_relax: f64,
    pub attached: u64,
    pub ruptures: u64,
    pub formations: u64,
}

/// An engine's fields as read, but for the typed ones (which [`Typed`] took).
pub(super) struct Untyped {
    pub formation: Formation,
    pub plate: Plate,
    pub integrator: Integrator,
    pub dt: f64,
    pub relax: f64,
    pub unstretched: bool,
    pub strong_off_threshold: f64,
    pub steps: u64,
    pub plate_x: f64,
    pub plate_v: f64,
    pub q: Vec<u8>,
    pub x: Vec<f64>,
    pub pending_dx: f64,
    pub pending_relax: f64,
    pub attached: u64,
    pub ruptures: u64,
    pub formations: u64,
}

/// Reads one typed field (law, bond or generator) into the caller's place for it.
pub(super) type Typed<'a, 'de> =
    &'a mut dyn FnMut(&mut dyn erased_serde::Deserializer<'de>) -> Result<(), erased_serde::Error>;

/// Reads an engine's map from `d`: the typed fields through `law`, `bond` and `rng`, the
/// others returned. Unknown fields are skipped; a missing or repeated one is an error.
pub(super) fn read<'de>(
    d: &mut dyn erased_serde::Deserializer<'de>,
    law: Typed<'_, 'de>,
    bond: Typed<'_, 'de>,
    rng: Typed<'_, 'de>,
) -> Result<Untyped, erased_serde::Error> {
    d.deserialize_struct("FixedEngine", &FIELDS, EngineVisitor { law, bond, rng })
}

struct EngineVisitor<'a, 'de> {
    law: Typed<'a, 'de>,
    bond: Typed<'a, 'de>,
    rng: Typed<'a, 'de>,
}

/// A typed field read through its [`Typed`] function.
struct Seed<'a, 'b, 'de>(&'b mut Typed<'a, 'de>);

impl<'de> DeserializeSeed<'de> for Seed<'_, '_, 'de> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        let mut erased = <dyn erased_serde::Deserializer>::erase(d);
        (self.0)(&mut erased).map_err(de::Error::custom)
    }
}

/// Stores `value` in `slot`, refusing a field given twice.
fn once<T, E: de::Error>(slot: &mut Option<T>, name: &'static str, value: T) -> Result<(), E> {
    if slot.replace(value).is_some() {
        return Err(E::duplicate_field(name));
    }
    Ok(())
}

impl<'de> Visitor<'de> for EngineVisitor<'_, 'de> {
    type Value = Untyped;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a fixed-step engine's state")
    }

    fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<Untyped, A::Error> {
        // Whether each of `TYPED` was read.
        let mut typed = [false; 3];
        let (mut formation, mut plate, mut integrator) = (None, None, None);
        let (mut dt, mut relax, mut unstretched, mut strong_off_threshold) = (None, None, None, None);
        let (mut steps, mut plate_x, mut plate_v, mut q, mut x) = (None, None, None, None, None);
        let (mut pending_dx, mut pending_relax) = (None, None);
        let (mut attached, mut ruptures, mut formations) = (None, None, None);
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                name @ ("law" | "bond" | "rng") => {
                    let (k, f) = match name {
                        "law" => (0, &mut self.law),
                        "bond" => (1, &mut self.bond),
                        _ => (2, &mut self.rng),
                    };
                    if std::mem::replace(&mut typed[k], true) {
                        return Err(de::Error::duplicate_field(TYPED[k]));
                    }
                    map.next_value_seed(Seed(f))?;
                }
                "flip" => {
                    map.next_value::<PhantomData<()>>()?;
                }
                "formation" => once(&mut formation, "formation", map.next_value()?)?,
                "plate" => once(&mut plate, "plate", map.next_value()?)?,
                "integrator" => once(&mut integrator, "integrator", map.next_value()?)?,
                "dt" => once(&mut dt, "dt", map.next_value()?)?,
                "relax" => once(&mut relax, "relax", map.next_value()?)?,
                "unstretched" => once(&mut unstretched, "unstretched", map.next_value()?)?,
                "strong_off_threshold" => once(&mut strong_off_threshold, "strong_off_threshold", map.next_value()?)?,
                "steps" => once(&mut steps, "steps", map.next_value()?)?,
                "plate_x" => once(&mut plate_x, "plate_x", map.next_value()?)?,
                "plate_v" => once(&mut plate_v, "plate_v", map.next_value()?)?,
                "q" => once(&mut q, "q", map.next_value()?)?,
                "x" => once(&mut x, "x", map.next_value()?)?,
                "pending_dx" => once(&mut pending_dx, "pending_dx", map.next_value()?)?,
                "pending_relax" => once(&mut pending_relax, "pending_relax", map.next_value()?)?,
                "attached" => once(&mut attached, "attached", map.next_value()?)?,
                "ruptures" => once(&mut ruptures, "ruptures", map.next_value()?)?,
                "formations" => once(&mut formations, "formations", map.next_value()?)?,
                _ => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        if let Some(k) = typed.iter().position(|&seen| !seen) {
            return Err(de::Error::missing_field(TYPED[k]));
        }
        fn need<T, E: de::Error>(v: Option<T>, name: &'static str) -> Result<T, E> {
            v.ok_or_else(|| E::missing_field(name))
        }
        Ok(Untyped {
            formation: need(formation, "formation")?,
            plate: need(plate, "plate")?,
            integrator: need(integrator, "integrator")?,
            dt: need(dt, "dt")?,
            relax: need(relax, "relax")?,
            unstretched: need(unstretched, "unstretched")?,
            strong_off_threshold: need(strong_off_threshold, "strong_off_threshold")?,
            steps: need(steps, "steps")?,
            plate_x: need(plate_x, "plate_x")?,
            plate_v: need(plate_v, "plate_v")?,
            q: need(q, "q")?,
            x: need(x, "x")?,
            pending_dx: need(pending_dx, "pending_dx")?,
            pending_relax: need(pending_relax, "pending_relax")?,
            attached: need(attached, "attached")?,
            ruptures: need(ruptures, "ruptures")?,
            formations: need(formations, "formations")?,
        })
    }
}

/// A typed field's value read from `d` into `slot`: the body of a [`Typed`] function.
pub(super) fn typed<'de, T: Deserialize<'de>>(
    slot: &mut Option<T>,
    d: &mut dyn erased_serde::Deserializer<'de>,
) -> Result<(), erased_serde::Error> {
    *slot = Some(erased_serde::deserialize(d)?);
    Ok(())
}
