//! Messages as JSON files, e.g. the `toolpath.json` that `cell hotwire` writes and `cell emit`
//! reads.
//!
//! JSON has no NaN or infinity: `serde_json` writes a non-finite float as `null`. [`from_str`]
//! reads `null` in a float field back as NaN, so a message survives the round trip with its bad
//! values intact and the consumer (the emitter) can name them, instead of the file failing to
//! parse. `null` anywhere else is an error like any other type mismatch.
//!
//! Errors name where the problem is: line and column for JSON syntax, the field path (e.g.
//! `segments[1].points[3].x`) for a missing field or a value of the wrong type.

use serde::de::{
    value::{MapDeserializer, SeqDeserializer},
    DeserializeOwned, Deserializer, IntoDeserializer, Visitor,
};
use serde_json::{Map, Value};

/// Why a JSON text is not a message of the requested type. One line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum JsonError {
    /// Not JSON at all.
    #[error("line {line} column {column}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// JSON, but not the message: a missing field or a value of the wrong type.
    #[error("{path}: {message}")]
    Shape {
        /// Field path, e.g. `segments[1].points[3].x` (`.` for the top level).
        path: String,
        /// What is wrong there.
        message: String,
    },
}

/// Reads a message of type `T` from JSON as `serde_json` writes it (module docs: `null` in a
/// float field is NaN).
///
/// # Errors
/// [`JsonError::Syntax`] with line and column, or [`JsonError::Shape`] with the field path.
pub fn from_str<T: DeserializeOwned>(text: &str) -> Result<T, JsonError> {
    let value: Value = serde_json::from_str(text).map_err(|e| JsonError::Syntax {
        line: e.line(),
        column: e.column(),
        message: strip_position(&e.to_string()),
    })?;
    serde_path_to_error::deserialize(Lenient(value)).map_err(|e| JsonError::Shape {
        path: e.path().to_string(),
        message: e.into_inner().to_string(),
    })
}

/// serde_json appends ` at line L column C` to its messages; the error carries them apart.
fn strip_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_owned(),
        None => message.to_owned(),
    }
}

/// A JSON value as a deserializer that reads `null` as NaN where a float is expected, at any
/// depth. Everything else behaves as `serde_json::Value`'s own deserializer.
struct Lenient(Value);

impl<'de> IntoDeserializer<'de, serde_json::Error> for Lenient {
    type Deserializer = Self;

    fn into_deserializer(self) -> Self {
        self
    }
}

fn visit_array<'de, V: Visitor<'de>>(
    items: Vec<Value>,
    visitor: V,
) -> Result<V::Value, serde_json::Error> {
    let mut seq = SeqDeserializer::new(items.into_iter().map(Lenient));
    let value = visitor.visit_seq(&mut seq)?;
    seq.end()?;
    Ok(value)
}

fn visit_object<'de, V: Visitor<'de>>(
    object: Map<String, Value>,
    visitor: V,
) -> Result<V::Value, serde_json::Error> {
    let mut map = MapDeserializer::new(object.into_iter().map(|(k, v)| (k, Lenient(v))));
    let value = visitor.visit_map(&mut map)?;
    map.end()?;
    Ok(value)
}

/// Methods that go straight to `serde_json::Value`.
macro_rules! forward {
    ($($method:ident)*) => {$(
        fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
            self.0.$method(visitor)
        }
    )*};
}

impl<'de> Deserializer<'de> for Lenient {
    type Error = serde_json::Error;

    forward! {
        deserialize_bool deserialize_i8 deserialize_i16 deserialize_i32 deserialize_i64
        deserialize_i128 deserialize_u8 deserialize_u16 deserialize_u32 deserialize_u64
        deserialize_u128 deserialize_char deserialize_str deserialize_string deserialize_bytes
        deserialize_byte_buf deserialize_unit deserialize_identifier deserialize_ignored_any
    }

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Array(items) => visit_array(items, visitor),
            Value::Object(object) => visit_object(object, visitor),
            other => other.deserialize_any(visitor),
        }
    }

    fn deserialize_f32<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Null => visitor.visit_f32(f32::NAN),
            other => other.deserialize_f32(visitor),
        }
    }

    fn deserialize_f64<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Null => visitor.visit_f64(f64::NAN),
            other => other.deserialize_f64(visitor),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Null => visitor.visit_none(),
            other => visitor.visit_some(Lenient(other)),
        }
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.0.deserialize_unit_struct(name, visitor)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        visitor.visit_newtype_struct(self)
    }

    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Array(items) => visit_array(items, visitor),
            other => other.deserialize_seq(visitor),
        }
    }

    fn deserialize_tuple<V: Visitor<'de>>(
        self,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Array(items) => visit_array(items, visitor),
            other => other.deserialize_tuple(len, visitor),
        }
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Array(items) => visit_array(items, visitor),
            other => other.deserialize_tuple_struct(name, len, visitor),
        }
    }

    fn deserialize_map<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Object(object) => visit_object(object, visitor),
            other => other.deserialize_map(visitor),
        }
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Object(object) => visit_object(object, visitor),
            Value::Array(items) => visit_array(items, visitor),
            other => other.deserialize_struct(name, fields, visitor),
        }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.0.deserialize_enum(name, variants, visitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{geometry_msgs::Point, Toolpath, ToolpathSegment};

    fn toolpath() -> Toolpath {
        Toolpath {
            job_id: "j".into(),
            segments: vec![ToolpathSegment {
                points: vec![
                    Point {
                        x: 1.0,
                        y: 2.0,
                        z: 0.0,
                    },
                    Point {
                        x: f64::NAN,
                        y: f64::INFINITY,
                        z: 0.5,
                    },
                ],
                feed_mm_s: vec![5.0, f32::NAN],
                power: vec![1.5, 2.5],
                ..Default::default()
            }],
            ..Default::default()
        }
    }

    #[test]
    fn round_trips_and_reads_null_floats_as_nan() {
        let text = serde_json::to_string_pretty(&toolpath()).unwrap();
        assert!(text.contains("null"), "serde_json writes NaN as null");
        let back: Toolpath = from_str(&text).unwrap();
        let s = &back.segments[0];
        assert_eq!(s.points[0], toolpath().segments[0].points[0]);
        assert!(s.points[1].x.is_nan() && s.points[1].y.is_nan());
        assert_eq!(s.points[1].z, 0.5);
        assert!(s.feed_mm_s[1].is_nan());
        assert_eq!((s.feed_mm_s[0], &s.power), (5.0, &vec![1.5, 2.5]));
        assert_eq!(back.job_id, "j");
    }

    #[test]
    fn errors_name_the_line_or_the_field() {
        let e = from_str::<Toolpath>("{\n  \"job_id\": \"j\",\n  oops\n}").unwrap_err();
        assert!(
            matches!(e, JsonError::Syntax { line: 3, .. }),
            "{e}: syntax errors carry the line"
        );
        assert!(!e.to_string().contains(" at line "), "{e}");

        let mut value = serde_json::to_value(toolpath()).unwrap();
        value["segments"][0]["points"][1]["y"] = serde_json::json!("high");
        let e = from_str::<Toolpath>(&value.to_string()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("segments[0].points[1].y: invalid type"),
            "{e}"
        );

        value["segments"][0]["points"][1]["y"] = serde_json::json!(1.0);
        value["segments"][0]["kind"] = Value::Null;
        let e = from_str::<Toolpath>(&value.to_string()).unwrap_err();
        assert!(e.to_string().starts_with("segments[0].kind:"), "{e}");

        value["segments"][0]["kind"] = serde_json::json!(1);
        value["segments"][0]
            .as_object_mut()
            .unwrap()
            .remove("normals");
        let e = from_str::<Toolpath>(&value.to_string()).unwrap_err();
        assert!(e.to_string().contains("missing field `normals`"), "{e}");
    }
}
