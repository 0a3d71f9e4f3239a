//! The check every stored value passes, written and read: no NaN anywhere in it; and the
//! check of every key's inputs: no NaN or infinity (JSON writes both as `null`, so +inf and
//! -inf would share a key).
//!
//! A point file's checksum finds corruption, not a forged value: a file written by hand with a
//! valid checksum decodes into any value of the right type. Each value is walked through its
//! own `Serialize` implementation (so every field of every stored type is seen, nested ones
//! included) and refused when a float is NaN: no computation of this crate stores one (an
//! unknown error is `None`, not NaN), so a NaN is a forgery or a fault, never a result.
//! Infinities pass: a main-to-side-lobe ratio without side lobes is +inf dB.
//!
//! Written by hand rather than through a value-tree crate: only floats are looked at, and
//! nothing is copied.

use serde::ser::{self, Serialize};
use std::fmt;

/// `Err` naming the first NaN in `value`.
pub fn refuse_nan<T: Serialize + ?Sized>(value: &T) -> Result<(), String> {
    let finder = NanFinder { infinities: false };
    value.serialize(finder).map_err(|e| e.0)
}

/// `Err` naming the first NaN or infinity in `value`.
pub fn refuse_non_finite<T: Serialize + ?Sized>(value: &T) -> Result<(), String> {
    let finder = NanFinder { infinities: true };
    value.serialize(finder).map_err(|e| e.0)
}

#[derive(Debug)]
struct Found(String);

impl fmt::Display for Found {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Found {}

impl ser::Error for Found {
    fn custom<M: fmt::Display>(message: M) -> Self {
        Found(message.to_string())
    }
}

/// A serializer that writes nothing and fails at the first NaN (or infinity, when asked).
#[derive(Clone, Copy)]
struct NanFinder {
    infinities: bool,
}

impl NanFinder {
    fn float(self, v: f64) -> Result<(), Found> {
        if v.is_nan() {
            Err(Found("holds a NaN".into()))
        } else if self.infinities && v.is_infinite() {
            Err(Found(format!("holds {v}")))
        } else {
            Ok(())
        }
    }
}

macro_rules! ignore {
    ($($name:ident: $t:ty),*) => {
        $(fn $name(self, _: $t) -> Result<(), Found> { Ok(()) })*
    };
}

impl ser::Serializer for NanFinder {
    type Ok = ();
    type Error = Found;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Self;
    type SerializeTupleVariant = Self;
    type SerializeMap = Self;
    type SerializeStruct = Self;
    type SerializeStructVariant = Self;

    ignore!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32,
        serialize_i64: i64, serialize_i128: i128, serialize_u8: u8, serialize_u16: u16,
        serialize_u32: u32, serialize_u64: u64, serialize_u128: u128, serialize_char: char,
        serialize_str: &str, serialize_bytes: &[u8], serialize_unit_struct: &'static str);

    fn serialize_f32(self, v: f32) -> Result<(), Found> {
        self.float(v.into())
    }
    fn serialize_f64(self, v: f64) -> Result<(), Found> {
        self.float(v)
    }
    fn serialize_none(self) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), Found> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<(), Found> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        v: &T,
    ) -> Result<(), Found> {
        v.serialize(self)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_tuple(self, _: usize) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, Found> {
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Found> {
        Ok(self)
    }
}

/// Elements, fields and map entries: each walked in turn; a struct field's name is added to
/// the message on the way out, so the error reads `holds a NaN in focus.peak.amplitude`.
impl NanFinder {
    fn element<T: Serialize + ?Sized>(self, v: &T) -> Result<(), Found> {
        v.serialize(self)
    }
    fn field<T: Serialize + ?Sized>(self, name: &str, v: &T) -> Result<(), Found> {
        v.serialize(self)
            .map_err(|Found(m)| match m.split_once(" in ") {
                Some((what, path)) => Found(format!("{what} in {name}.{path}")),
                None => Found(format!("{m} in {name}")),
            })
    }
}

macro_rules! walk_elements {
    ($($t:path: $m:ident),*) => {$(
        impl $t for NanFinder {
            type Ok = ();
            type Error = Found;
            fn $m<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), Found> {
                self.element(v)
            }
            fn end(self) -> Result<(), Found> {
                Ok(())
            }
        }
    )*};
}

walk_elements!(ser::SerializeSeq: serialize_element, ser::SerializeTuple: serialize_element,
    ser::SerializeTupleStruct: serialize_field, ser::SerializeTupleVariant: serialize_field);

macro_rules! walk_fields {
    ($($t:path),*) => {$(
        impl $t for NanFinder {
            type Ok = ();
            type Error = Found;
            fn serialize_field<T: Serialize + ?Sized>(
                &mut self,
                name: &'static str,
                v: &T,
            ) -> Result<(), Found> {
                self.field(name, v)
            }
            fn end(self) -> Result<(), Found> {
                Ok(())
            }
        }
    )*};
}

walk_fields!(ser::SerializeStruct, ser::SerializeStructVariant);

impl ser::SerializeMap for NanFinder {
    type Ok = ();
    type Error = Found;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, k: &T) -> Result<(), Found> {
        self.element(k)
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), Found> {
        self.element(v)
    }
    fn end(self) -> Result<(), Found> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{refuse_nan, refuse_non_finite};
    use std::collections::BTreeMap;

    #[derive(serde::Serialize)]
    struct Peak {
        time_s: f64,
        amplitude: f64,
    }

    #[derive(serde::Serialize)]
    struct Focus {
        peak: Peak,
        traces: Vec<Vec<f32>>,
        error: Option<f64>,
    }

    #[test]
    fn finds_a_nan_at_any_depth_and_names_its_field() {
        let focus = |amplitude, sample, error| Focus {
            peak: Peak {
                time_s: 1e-6,
                amplitude,
            },
            traces: vec![vec![0.0, sample]],
            error,
        };
        assert_eq!(refuse_nan(&focus(1.0, 2.0, None)), Ok(()));
        assert_eq!(refuse_nan(&focus(f64::INFINITY, 2.0, Some(-0.0))), Ok(()));
        assert_eq!(
            refuse_nan(&focus(f64::NAN, 2.0, None)),
            Err("holds a NaN in peak.amplitude".into())
        );
        assert_eq!(
            refuse_nan(&focus(1.0, f32::NAN, None)),
            Err("holds a NaN in traces".into())
        );
        assert_eq!(
            refuse_nan(&focus(1.0, 2.0, Some(f64::NAN))),
            Err("holds a NaN in error".into())
        );
        let map = BTreeMap::from([("a", vec![(1u8, f64::NAN)])]);
        assert!(refuse_nan(&map).is_err());
        assert_eq!(
            refuse_non_finite(&focus(f64::NEG_INFINITY, 2.0, None)),
            Err("holds -inf in peak.amplitude".into())
        );
        assert_eq!(refuse_non_finite(&focus(1.0, 2.0, Some(3.0))), Ok(()));
    }
}
