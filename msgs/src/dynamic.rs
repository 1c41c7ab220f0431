//! Definition-driven CDR decoding: turns a ROS 2 serialized message into JSON using only its
//! `.msg` definitions, with no Rust type. Used by the drift test and by bag tools.
//!
//! Hand-written: existing CDR crates need a Rust type at compile time.
//!
//! Mapping: integers and `byte`/`char` become JSON integers, floats JSON numbers (`float32`
//! widened with `as f64`; NaN and infinities become `null`, as in `serde_json`), `bool` a JSON
//! bool, `string` a JSON string, arrays JSON arrays and messages JSON objects keyed by field name.
//! `wstring` is not supported (its CDR layout differs between DDS vendors).

use std::collections::HashMap;
use std::fmt;

use serde_json::{Map, Value};

use crate::cdr::{self, CdrError, Endianness};
use crate::idl::{self, Array, BaseType, FieldType, MessageSpec, ParseError, Primitive};
use crate::registry::{self, RegistryError};

/// Deepest message nesting decoded; guards against recursive definitions.
const MAX_DEPTH: usize = 64;

/// Why a message could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    /// The type (or one it uses) has no definition.
    #[error("no definition for message type `{0}`")]
    UnknownType(String),
    /// A definition does not parse.
    #[error(transparent)]
    Definition(#[from] ParseError),
    /// A complete (`ros2msg`) definition is not laid out as rosbag2 writes it.
    #[error("malformed complete message definition: {0}")]
    FullDefinition(String),
    /// Bad encapsulation header or trailing bytes.
    #[error(transparent)]
    Cdr(#[from] CdrError),
    /// The body ended early.
    #[error("{path}: need {needed} bytes at body offset {offset}, {available} left")]
    Eof {
        /// Field being read, e.g. `segments[1].points[0].x`.
        path: String,
        /// Offset into the body (after the header).
        offset: usize,
        /// Bytes needed.
        needed: usize,
        /// Bytes left.
        available: usize,
    },
    /// A value is invalid for its type (bool not 0/1, bad string, bound exceeded, ...).
    #[error("{path}: {reason} at body offset {offset}")]
    Invalid {
        /// Field being read.
        path: String,
        /// Offset into the body.
        offset: usize,
        /// What is wrong.
        reason: String,
    },
}

impl From<RegistryError> for DecodeError {
    fn from(e: RegistryError) -> Self {
        match e {
            RegistryError::Unknown(name) => Self::UnknownType(name),
            RegistryError::Parse(p) => Self::Definition(p),
        }
    }
}

/// Decodes a serialized message (encapsulation header + CDR body) of a registered type.
/// Parses the definitions on every call: to decode many messages, build a [`Schema`] once.
pub fn decode(ros_name: &str, bytes: &[u8]) -> Result<Value, DecodeError> {
    Schema::from_registry(ros_name)?.decode(bytes)
}

/// A message type with the definitions of every type it uses, ready to decode.
#[derive(Debug, Clone)]
pub struct Schema {
    root: String,
    specs: HashMap<String, MessageSpec>,
}

impl Schema {
    /// Builds the schema of a registered type from the embedded interface files.
    pub fn from_registry(ros_name: &str) -> Result<Self, DecodeError> {
        let mut specs = HashMap::new();
        let mut todo = vec![ros_name.to_owned()];
        while let Some(name) = todo.pop() {
            if specs.contains_key(&name) {
                continue;
            }
            let spec = registry::spec(&name)?;
            todo.extend(spec.dependencies().into_iter().map(str::to_owned));
            specs.insert(name, spec);
        }
        Ok(Self {
            root: ros_name.to_owned(),
            specs,
        })
    }

    /// Builds a schema from a rosbag2 `ros2msg` complete definition (as stored in bags and in
    /// [`registry::full_definition`]); `ros_name` names the top-level type. Dependency headers
    /// may be `MSG: pkg/Type` or `MSG: pkg/msg/Type`. Parse errors carry the dependency's name
    /// and the line number within the whole text.
    pub fn from_full_definition(ros_name: &str, text: &str) -> Result<Self, DecodeError> {
        let lines: Vec<&str> = text.lines().collect();
        // (type name, index of first line, lines) of each section.
        let mut sections = vec![(ros_name.to_owned(), 0, Vec::new())];
        let mut i = 0;
        while i < lines.len() {
            if lines[i] == registry::DELIMITER {
                let header = lines.get(i + 1).copied().unwrap_or_default();
                let name = header.strip_prefix("MSG: ").ok_or_else(|| {
                    DecodeError::FullDefinition(format!(
                        "line {}: expected `MSG: pkg/msg/Type`",
                        i + 2
                    ))
                })?;
                let name = match name.trim().split('/').collect::<Vec<_>>().as_slice() {
                    [pkg, ty] | [pkg, "msg", ty] => format!("{pkg}/msg/{ty}"),
                    _ => {
                        return Err(DecodeError::FullDefinition(format!(
                            "line {}: bad type `{name}`",
                            i + 2
                        )))
                    }
                };
                sections.push((name, i + 2, Vec::new()));
                i += 2;
                continue;
            }
            if let Some(last) = sections.last_mut() {
                last.2.push(lines[i]);
            }
            i += 1;
        }
        let mut specs = HashMap::new();
        for (name, first, body) in sections {
            let spec = idl::parse_section(&name, &name, first + 1, &body.join("\n"))?;
            specs.insert(name, spec);
        }
        Ok(Self {
            root: ros_name.to_owned(),
            specs,
        })
    }

    /// Name of the top-level type.
    pub fn root(&self) -> &str {
        &self.root
    }

    /// Decodes a serialized message (encapsulation header + CDR body) into JSON. Fails if the
    /// body is too short or more than 3 padding bytes follow the message.
    pub fn decode(&self, bytes: &[u8]) -> Result<Value, DecodeError> {
        let (endianness, body) = cdr::split_header(bytes)?;
        let mut reader = Reader {
            schema: self,
            body,
            pos: 0,
            big: endianness == Endianness::Big,
            path: Vec::new(),
        };
        let value = reader.message(&self.root, 0)?;
        cdr::check_trailing(body.len() - reader.pos)?;
        Ok(value)
    }
}

/// One step of the path to the value being read, for error messages.
enum Step<'s> {
    Field(&'s str),
    Index(usize),
}

/// Cursor over a CDR body; alignment is relative to the body start.
struct Reader<'s, 'b> {
    schema: &'s Schema,
    body: &'b [u8],
    pos: usize,
    big: bool,
    path: Vec<Step<'s>>,
}

impl fmt::Display for Reader<'_, '_> {
    /// Formats the current path, e.g. `segments[1].points[0].x`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            return f.write_str(&self.schema.root);
        }
        for (i, step) in self.path.iter().enumerate() {
            match step {
                Step::Field(name) if i == 0 => write!(f, "{name}")?,
                Step::Field(name) => write!(f, ".{name}")?,
                Step::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

impl<'s, 'b> Reader<'s, 'b> {
    fn invalid(&self, reason: impl Into<String>) -> DecodeError {
        DecodeError::Invalid {
            path: self.to_string(),
            offset: self.pos,
            reason: reason.into(),
        }
    }

    fn left(&self) -> usize {
        self.body.len() - self.pos
    }

    fn take(&mut self, n: usize) -> Result<&'b [u8], DecodeError> {
        if n > self.left() {
            return Err(DecodeError::Eof {
                path: self.to_string(),
                offset: self.pos,
                needed: n,
                available: self.left(),
            });
        }
        self.pos += n;
        Ok(&self.body[self.pos - n..self.pos])
    }

    /// Reads an `N`-byte number after aligning to `N`, as big-endian bytes.
    fn number<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        let pad = (N - self.pos % N) % N;
        self.take(pad)?;
        let big = self.big;
        let mut out: [u8; N] = self
            .take(N)?
            .try_into()
            .map_err(|_| self.invalid("short read"))?;
        if !big {
            out.reverse();
        }
        Ok(out)
    }

    fn u32(&mut self) -> Result<u32, DecodeError> {
        self.number::<4>().map(u32::from_be_bytes)
    }

    fn message(&mut self, name: &str, depth: usize) -> Result<Value, DecodeError> {
        let schema = self.schema;
        let spec = schema
            .specs
            .get(name)
            .ok_or_else(|| DecodeError::UnknownType(name.to_owned()))?;
        if depth > MAX_DEPTH {
            return Err(self.invalid(format!("messages nested deeper than {MAX_DEPTH}")));
        }
        if spec.fields.is_empty() {
            // rosidl gives empty messages one `uint8 structure_needs_at_least_one_member`.
            self.take(1)?;
        }
        let mut map = Map::new();
        for field in &spec.fields {
            self.path.push(Step::Field(&field.name));
            let value = self.field(&field.ty, depth)?;
            self.path.pop();
            map.insert(field.name.clone(), value);
        }
        Ok(Value::Object(map))
    }

    fn field(&mut self, ty: &'s FieldType, depth: usize) -> Result<Value, DecodeError> {
        let count = match ty.array {
            None => return self.single(&ty.base, depth),
            Some(Array::Fixed(n)) => n,
            Some(Array::Unbounded) => self.u32()? as usize,
            Some(Array::Bounded(max)) => {
                let n = self.u32()? as usize;
                if n > max {
                    return Err(
                        self.invalid(format!("sequence of {n} elements exceeds its bound {max}"))
                    );
                }
                n
            }
        };
        // Every element takes at least one byte, so a bigger count cannot be satisfied.
        if count > self.left() {
            return Err(self.invalid(format!(
                "{count} elements announced, only {} bytes left",
                self.left()
            )));
        }
        let mut items = Vec::with_capacity(count);
        for i in 0..count {
            self.path.push(Step::Index(i));
            items.push(self.single(&ty.base, depth)?);
            self.path.pop();
        }
        Ok(Value::Array(items))
    }

    fn single(&mut self, base: &BaseType, depth: usize) -> Result<Value, DecodeError> {
        use Primitive::*;
        let prim = match base {
            BaseType::Message(name) => return self.message(name, depth + 1),
            BaseType::Primitive(p) => *p,
        };
        Ok(match prim {
            Bool => match self.take(1)?[0] {
                0 => Value::Bool(false),
                1 => Value::Bool(true),
                b => return Err(self.invalid(format!("bool byte {b} is not 0 or 1"))),
            },
            Byte | Char | Uint8 => Value::from(self.take(1)?[0]),
            Int8 => Value::from(self.take(1)?[0] as i8),
            Int16 => Value::from(i16::from_be_bytes(self.number()?)),
            Uint16 => Value::from(u16::from_be_bytes(self.number()?)),
            Int32 => Value::from(i32::from_be_bytes(self.number()?)),
            Uint32 => Value::from(u32::from_be_bytes(self.number()?)),
            Int64 => Value::from(i64::from_be_bytes(self.number()?)),
            Uint64 => Value::from(u64::from_be_bytes(self.number()?)),
            Float32 => Value::from(f32::from_be_bytes(self.number()?) as f64),
            Float64 => Value::from(f64::from_be_bytes(self.number()?)),
            String { max_len } => Value::String(self.string(max_len)?),
            WString { .. } => return Err(self.invalid("wstring is not supported")),
        })
    }

    /// A CDR string: u32 length including the NUL terminator, the bytes, then NUL.
    fn string(&mut self, max_len: Option<usize>) -> Result<String, DecodeError> {
        let len = self.u32()? as usize;
        let start = self.pos;
        let bytes = self.take(len)?;
        // Some DDS implementations send an empty string as length 0 with no terminator.
        let text = match bytes.split_last() {
            None => &[][..],
            Some((0, text)) => text,
            Some(_) => {
                self.pos = start;
                return Err(self.invalid("string is not NUL-terminated"));
            }
        };
        let text = match std::str::from_utf8(text) {
            Ok(s) => s.to_owned(),
            Err(e) => {
                self.pos = start;
                return Err(self.invalid(format!("string is not UTF-8 ({e})")));
            }
        };
        match max_len {
            Some(max) if text.len() > max => Err(self.invalid(format!(
                "string of {} bytes exceeds its bound {max}",
                text.len()
            ))),
            _ => Ok(text),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cdr::to_cdr;
    use serde_json::json;

    fn schema(text: &str) -> Schema {
        Schema::from_full_definition("t/msg/T", text).expect("parses")
    }

    #[test]
    fn decodes_alignment_strings_and_fixed_arrays() {
        let s = schema("uint8 a\nfloat64 b\nstring c\nint16[2] d\nbool e\nuint32[] f");
        // Header, a=1, pad 7, b=0.5, c="hi", d=[-1, 2] (no length), e=true, pad 3, f=[9].
        let mut bytes = vec![0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0];
        bytes.extend(0.5f64.to_le_bytes());
        bytes.extend([3, 0, 0, 0, b'h', b'i', 0, 0]); // the last 0 aligns `d` to 2
        bytes.extend([0xff, 0xff, 2, 0, 1, 0, 0, 0, 1, 0, 0, 0, 9, 0, 0, 0]);
        let value = s.decode(&bytes).expect("decodes");
        assert_eq!(
            value,
            json!({"a": 1, "b": 0.5, "c": "hi", "d": [-1, 2], "e": true, "f": [9]})
        );
    }

    #[test]
    fn big_endian_and_padding() {
        let s = schema("uint16 a\nuint32 b");
        assert_eq!(
            s.decode(&[0, 0, 0, 0, 1, 2, 0, 0, 0, 0, 0, 3]).expect("BE"),
            json!({"a": 258, "b": 3})
        );
        let mut le = vec![0, 1, 0, 0, 2, 1, 0, 0, 3, 0, 0, 0];
        le.extend([0, 0, 0]);
        assert!(s.decode(&le).is_ok(), "up to 3 padding bytes");
        le.push(0);
        assert!(matches!(
            s.decode(&le),
            Err(DecodeError::Cdr(CdrError::Trailing(4)))
        ));
    }

    #[test]
    fn errors_name_the_field() {
        let s = schema("uint8 a\nP[] ps\n================================================================================\nMSG: t/P\nbool ok\nstring name");
        let bytes = [
            0, 1, 0, 0, 5, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, b'x', 0, 2,
        ];
        let err = s.decode(&bytes).expect_err("bad bool in ps[1]").to_string();
        assert!(err.starts_with("ps[1].ok: bool byte 2"), "{err}");

        let huge = [0, 1, 0, 0, 5, 0, 0, 0, 0xff, 0xff, 0xff, 0xff];
        let err = s.decode(&huge).expect_err("count too big").to_string();
        assert!(err.contains("4294967295 elements announced"), "{err}");
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        let seg = crate::ToolpathSegment {
            kind: 1,
            points: vec![Default::default(); 2],
            feed_mm_s: vec![1.0, 2.0],
            ..Default::default()
        };
        let bytes = to_cdr(&seg).expect("serializes");
        let s = Schema::from_registry("cell_msgs/msg/ToolpathSegment").expect("registered");
        assert!(s.decode(&bytes).is_ok());
        for n in 0..bytes.len() {
            assert!(s.decode(&bytes[..n]).is_err(), "truncated to {n}");
        }
        for i in 0..bytes.len() {
            for v in [0x00, 0x80, 0xff] {
                let mut bad = bytes.clone();
                bad[i] = v;
                let _ = s.decode(&bad);
            }
        }
    }

    #[test]
    fn recursive_definitions_stop() {
        let s = schema("t/T inner");
        let err = s.decode(&[0, 1, 0, 0]).expect_err("infinite nesting");
        assert!(err.to_string().contains("nested deeper"), "{err}");
        assert!(matches!(
            decode("nope/msg/X", &[0, 1, 0, 0]),
            Err(DecodeError::UnknownType(_))
        ));
    }
}
