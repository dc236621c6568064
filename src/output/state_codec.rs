//! The MessagePack codec of engine states (checkpoints and `Simulation::state`), with the
//! format's code compiled once.
//!
//! Every engine type has its own serde visitor, and `rmp-serde` would compile its decoder
//! and encoder once per visitor and value type: a fifth of the library's machine code, for
//! dozens of engine variants. Going through `erased-serde` (a type-erased `Serializer` and
//! `Deserializer`) keeps one copy of the format's code; the engines' own serde code is
//! unchanged, and so are the bytes (structs as maps with their field names, every `f64`
//! bit for bit). A state is encoded or decoded once per checkpoint or restore, so the
//! virtual call per value costs nothing that matters.

use std::io::Write;

use serde::{Deserialize, Serialize};

/// Why a state could not be encoded or decoded (the format's message).
pub type CodecError = erased_serde::Error;

/// Writes `value` to `w` as MessagePack, structs as maps with their field names.
pub fn encode<W: Write, T: Serialize + ?Sized>(w: W, value: &T) -> Result<(), rmp_serde::encode::Error> {
    let mut ser = rmp_serde::Serializer::new(w).with_struct_map();
    erased_serde::serialize(value, &mut ser)
}

/// Reads a `T` from MessagePack `bytes` (as written by [`encode`]).
pub fn decode<'de, T: Deserialize<'de>>(bytes: &'de [u8]) -> Result<T, CodecError> {
    let mut de = rmp_serde::Deserializer::from_read_ref(bytes);
    let mut erased = <dyn erased_serde::Deserializer>::erase(&mut de);
    erased_serde::deserialize(&mut erased)
}

/// Splits the bytes of a pair `(name, value)` written by [`encode`] into the name and the
/// bytes of the value (decode those with [`decode`]). Reading the pair's array header and
/// its string here, rather than decoding a tuple type, keeps the tuple's decoder from being
/// compiled once per value type.
pub fn split_named(bytes: &[u8]) -> Result<(&str, &[u8]), CodecError> {
    use serde::de::Error;
    let mut rest = bytes;
    match rmp::decode::read_array_len(&mut rest) {
        Ok(2) => {}
        Ok(len) => return Err(CodecError::invalid_length(len as usize, &"a pair (name, state)")),
        Err(e) => return Err(CodecError::custom(format_args!("not a pair (name, state): {e}"))),
    }
    rmp::decode::read_str_from_slice(rest).map_err(|e| CodecError::custom(format_args!("no name: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct S {
        a: f64,
        b: Option<u32>,
        v: Vec<f64>,
        name: String,
    }

    /// The bytes are those of plain `rmp-serde` with struct maps, and they read back.
    #[test]
    fn bytes_are_plain_messagepack_and_round_trip() {
        let s = S { a: f64::INFINITY, b: None, v: vec![0.1, -0.0, f64::MIN_POSITIVE], name: "x".into() };
        let mut ours = Vec::new();
        encode(&mut ours, &s).unwrap();
        let mut plain = Vec::new();
        s.serialize(&mut rmp_serde::Serializer::new(&mut plain).with_struct_map()).unwrap();
        assert_eq!(ours, plain);
        let back: S = decode(&ours).unwrap();
        assert_eq!(
            back.v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            s.v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(back, s);
        let plain_back: S = rmp_serde::from_slice(&plain).unwrap();
        assert_eq!(plain_back, s);
    }

    /// A pair's name and value read apart are those of the pair; anything else is an error.
    #[test]
    fn a_named_pair_splits_into_its_name_and_value() {
        let s = S { a: -2.5, b: Some(7), v: vec![1.0, f64::NAN], name: "z".into() };
        let mut bytes = Vec::new();
        encode(&mut bytes, &("stickslip::Engine<A, B>", &s)).unwrap();
        let (name, body) = split_named(&bytes).unwrap();
        assert_eq!(name, "stickslip::Engine<A, B>");
        let back: S = decode(body).unwrap();
        assert_eq!((back.a, back.b, back.name.as_str()), (-2.5, Some(7), "z"));
        assert_eq!(back.v[0], 1.0);
        assert!(back.v[1].is_nan());
        let mut three = Vec::new();
        encode(&mut three, &("a", 1u8, 2u8)).unwrap();
        assert!(split_named(&three).is_err());
        let mut unnamed = Vec::new();
        encode(&mut unnamed, &(3u8, &s)).unwrap();
        assert!(split_named(&unnamed).is_err());
        assert!(split_named(&[]).is_err());
        assert!(split_named(&bytes[..3]).is_err());
    }

    #[test]
    fn truncated_bytes_are_an_error() {
        let mut bytes = Vec::new();
        encode(&mut bytes, &S { a: 1.0, b: Some(2), v: vec![1.0; 4], name: "y".into() }).unwrap();
        bytes.truncate(bytes.len() - 3);
        assert!(decode::<S>(&bytes).is_err());
    }
}
