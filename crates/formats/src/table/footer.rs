//! A structural check of a Parquet footer before polars parses it.
//!
//! Takes the bytes of a Parquet file; gives `Ok` when its footer (the `FileMetaData` thrift
//! struct in the compact protocol) is well formed enough to parse without unbounded
//! allocations or recursion, or a [`FooterError`] saying why it is not.
//!
//! polars-parquet's footer decoder sizes each list from its header before reading it
//! (`Vec::with_capacity(size)`): a corrupt size of 2^31 row groups asks for hundreds of
//! gigabytes and *aborts* the process, which no panic guard catches (the fuzzer found 13
//! such files, now regression fixtures in `fuzz/regressions/`). This walker reads the same
//! bytes the way that decoder does: it knows the Parquet `FileMetaData` schema (the
//! structs and field ids polars decodes, [`expect`]) and refuses a known field whose wire
//! type is not the one the decoder will read it as (the decoder does not look at the
//! type, so a mutated type makes it read a list header out of other bytes), any list,
//! set, map or binary claiming more elements or bytes than remain in the footer (each
//! element takes at least one byte; a known list's size is taken as the decoder's i32), nesting deeper than [`MAX_DEPTH`], and a footer length or magic that does not
//! fit the file. Unknown fields are skipped by their wire type, as the decoder does (a
//! list of booleans, which the decoder's skipper reads as zero bytes but the protocol as
//! one byte each, is refused: no Parquet footer holds one). Long-form field ids are
//! zigzag-decoded from the whole varint and then cut to 16 bits, as the decoder does. The
//! schema's nesting (`num_children` chains, which the decoder walks recursively) is
//! limited to [`MAX_DEPTH`] levels. Written by hand
//! because no crate exposes a bounded compact-protocol skipper over a byte slice without
//! pulling in the Apache `thrift` runtime (whose own skipper has the same pre-sizing).

/// Deepest struct/list nesting accepted (the Parquet schema nests a handful deep).
pub const MAX_DEPTH: usize = 64;

/// Why a footer is refused (one line, for the error naming the file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct FooterError(String);

impl From<String> for FooterError {
    fn from(s: String) -> Self {
        FooterError(s)
    }
}

/// Check the footer of a whole Parquet file held in `file`.
pub fn check(file: &[u8]) -> Result<(), FooterError> {
    check_str(file).map_err(FooterError)
}

fn check_str(file: &[u8]) -> Result<(), String> {
    let n = file.len();
    if n < 12 || &file[..4] != b"PAR1" || &file[n - 4..] != b"PAR1" {
        return Err("not a Parquet file (magic `PAR1` missing at its start or end)".into());
    }
    let len = u32::from_le_bytes(file[n - 8..n - 4].try_into().expect("4 bytes")) as usize;
    if len > n - 12 {
        return Err(format!(
            "footer length {len} larger than the file's {} bytes",
            n - 12
        ));
    }
    let mut w = Walker {
        buf: &file[n - 8 - len..n - 8],
        pos: 0,
        children: Vec::new(),
    };
    w.skip_struct(Kind::FileMeta, 0)?;
    schema_depth(&w.children)
}

/// The schema's elements come depth-first, each with its `num_children`: the depth of
/// that tree must stay within [`MAX_DEPTH`] (the decoder recurses once per level).
fn schema_depth(children: &[i64]) -> Result<(), String> {
    // remaining children of each open level
    let mut open: Vec<i64> = Vec::new();
    for &c in children {
        while open.last() == Some(&0) {
            open.pop();
        }
        if let Some(top) = open.last_mut() {
            *top -= 1;
        }
        if c > 0 {
            open.push(c);
            if open.len() > MAX_DEPTH {
                return Err(format!("footer schema nested deeper than {MAX_DEPTH}"));
            }
        }
    }
    Ok(())
}

/// The structs of the Parquet footer that polars decodes field by field.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    FileMeta,
    SchemaElement,
    RowGroup,
    ColumnChunk,
    ColumnMeta,
    Statistics,
    KeyValue,
    SortingColumn,
    ColumnOrder,
    LogicalType,
    Decimal,
    TimeUnit,
    Time,
    IntType,
    /// A struct whose fields are all skipped by their wire type.
    Opaque,
}

/// How the decoder reads a known field.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    /// A varint (i16/i32/i64).
    Varint,
    /// A binary or string.
    Binary,
    /// One raw byte (i8).
    Byte,
    /// A boolean (in the field header).
    Bool,
    /// A struct.
    Struct(Kind),
    /// A list of varints.
    ListVarint,
    /// A list of binaries.
    ListBinary,
    /// A list of structs.
    ListStruct(Kind),
}

/// The field `id` of struct `kind` as polars-parquet 0.55's footer decoder reads it
/// (`handwritten_thrift/file_metadata_thrift.rs`); `None`: skipped by its wire type.
fn expect(kind: Kind, id: i64) -> Option<Expect> {
    use Expect::*;
    use Kind::*;
    Some(match (kind, id) {
        (FileMeta, 1 | 3) => Varint,
        (FileMeta, 2) => ListStruct(SchemaElement),
        (FileMeta, 4) => ListStruct(RowGroup),
        (FileMeta, 5) => ListStruct(KeyValue),
        (FileMeta, 6) => Binary,
        (FileMeta, 7) => ListStruct(ColumnOrder),
        (SchemaElement, 1..=3 | 5..=9) => Varint,
        (SchemaElement, 4) => Binary,
        (SchemaElement, 10) => Struct(LogicalType),
        (RowGroup, 1) => ListStruct(ColumnChunk),
        (RowGroup, 2 | 3 | 5..=7) => Varint,
        (RowGroup, 4) => ListStruct(SortingColumn),
        (ColumnChunk, 1) => Binary,
        (ColumnChunk, 2 | 4..=7) => Varint,
        (ColumnChunk, 3) => Struct(ColumnMeta),
        (ColumnMeta, 1 | 4..=7 | 9..=11 | 14 | 15) => Varint,
        (ColumnMeta, 2) => ListVarint,
        (ColumnMeta, 3) => ListBinary,
        (ColumnMeta, 12) => Struct(Statistics),
        (Statistics, 1 | 2 | 5 | 6) => Binary,
        (Statistics, 3 | 4) => Varint,
        (Statistics, 7 | 8) => Bool,
        (KeyValue, 1 | 2) => Binary,
        (SortingColumn, 1) => Varint,
        (SortingColumn, 2 | 3) => Bool,
        (ColumnOrder, 1 | 2) => Struct(Opaque),
        (LogicalType, 1..=4 | 6 | 11..=15) => Struct(Opaque),
        (LogicalType, 5) => Struct(Decimal),
        (LogicalType, 7 | 8) => Struct(Time),
        (LogicalType, 10) => Struct(IntType),
        (Decimal, 1 | 2) => Varint,
        (TimeUnit, 1..=3) => Struct(Opaque),
        (Time, 1) => Bool,
        (Time, 2) => Struct(TimeUnit),
        (IntType, 1) => Byte,
        (IntType, 2) => Bool,
        _ => return None,
    })
}

/// The compact protocol's element types.
const BOOL_TRUE: u8 = 1;
const BOOL_FALSE: u8 = 2;
const BYTE: u8 = 3;
const I16: u8 = 4;
const I32: u8 = 5;
const I64: u8 = 6;
const DOUBLE: u8 = 7;
const BINARY: u8 = 8;
const LIST: u8 = 9;
const SET: u8 = 10;
const MAP: u8 = 11;
const STRUCT: u8 = 12;
const UUID: u8 = 13;

struct Walker<'a> {
    buf: &'a [u8],
    pos: usize,
    /// `num_children` of every schema element read, in order (0 when absent).
    children: Vec<i64>,
}

impl Walker<'_> {
    fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    fn byte(&mut self) -> Result<u8, String> {
        let b = *self
            .buf
            .get(self.pos)
            .ok_or_else(|| format!("footer truncated at byte {}", self.pos))?;
        self.pos += 1;
        Ok(b)
    }

    fn skip(&mut self, n: usize) -> Result<(), String> {
        if n > self.remaining() {
            return Err(format!(
                "footer field of {n} bytes at byte {} past its end ({} left)",
                self.pos,
                self.remaining()
            ));
        }
        self.pos += n;
        Ok(())
    }

    fn varint(&mut self) -> Result<u64, String> {
        let mut v = 0u64;
        for i in 0..10 {
            let b = self.byte()?;
            v |= u64::from(b & 0x7f) << (7 * i);
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(format!(
            "footer varint longer than 10 bytes at byte {}",
            self.pos
        ))
    }

    /// A collection of `size` elements needs at least `size × min_bytes` bytes.
    fn check_size(&self, size: u64, min_bytes: u64, what: &str) -> Result<usize, String> {
        if size.saturating_mul(min_bytes) > self.remaining() as u64 {
            return Err(format!(
                "footer {what} of {size} elements at byte {} with {} bytes left",
                self.pos,
                self.remaining()
            ));
        }
        Ok(size as usize)
    }

    /// A list or set header: the element type and the size as written (a long size
    /// follows as a varint).
    fn list_header(&mut self) -> Result<(u8, u64), String> {
        let h = self.byte()?;
        let size = match h >> 4 {
            15 => self.varint()?,
            s => u64::from(s),
        };
        Ok((h & 0x0f, size))
    }

    fn skip_value(&mut self, ty: u8, depth: usize, in_collection: bool) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!("footer nested deeper than {MAX_DEPTH}"));
        }
        match ty {
            // a field's boolean lives in its type; in a collection the protocol gives it a
            // byte but the decoder's skipper none: refused there (see the module docs)
            BOOL_TRUE | BOOL_FALSE => {
                if in_collection {
                    return Err(format!(
                        "footer collection of booleans at byte {}",
                        self.pos
                    ));
                }
                Ok(())
            }
            BYTE => self.byte().map(|_| ()),
            I16 | I32 | I64 => self.varint().map(|_| ()),
            DOUBLE => self.skip(8),
            UUID => self.skip(16),
            BINARY => {
                let len = self.varint()?;
                let len = self.check_size(len, 1, "binary")?;
                self.skip(len)
            }
            LIST | SET => {
                let (elem, size) = self.list_header()?;
                let size = self.check_size(size, 1, "list")?;
                for _ in 0..size {
                    self.skip_value(elem, depth + 1, true)?;
                }
                Ok(())
            }
            MAP => {
                let size = self.varint()?;
                let size = self.check_size(size, 2, "map")?;
                if size > 0 {
                    let kv = self.byte()?;
                    for _ in 0..size {
                        self.skip_value(kv >> 4, depth + 1, true)?;
                        self.skip_value(kv & 0x0f, depth + 1, true)?;
                    }
                }
                Ok(())
            }
            STRUCT => self.skip_struct(Kind::Opaque, depth + 1),
            t => Err(format!(
                "footer holds unknown type {t} at byte {}",
                self.pos
            )),
        }
    }

    fn skip_struct(&mut self, kind: Kind, depth: usize) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!("footer nested deeper than {MAX_DEPTH}"));
        }
        let mut last_id: i64 = 0;
        let mut children = 0i64;
        loop {
            let h = self.byte()?;
            if h == 0 {
                if kind == Kind::SchemaElement {
                    self.children.push(children);
                }
                return Ok(());
            }
            let ty = h & 0x0f;
            let id = match h >> 4 {
                // a long-form field id follows (zigzag i16)
                // (zigzag over the whole varint, then cut to i16, as the decoder does)
                0 => {
                    let v = self.varint()?;
                    (((v >> 1) as i64) ^ -((v & 1) as i64)) as i16 as i64
                }
                delta => last_id + i64::from(delta),
            };
            if kind == Kind::SchemaElement && id == 5 && matches!(ty, I16 | I32 | I64) {
                let v = self.varint()?;
                // zigzag, taken as the decoder's i32
                children = (((v >> 1) as i64) ^ -((v & 1) as i64)) as i32 as i64;
            } else {
                match expect(kind, id) {
                    None => self.skip_value(ty, depth, false)?,
                    Some(e) => self.read_expected(kind, id, ty, e, depth)?,
                }
            }
            last_id = id;
        }
    }

    /// A known field: its wire type must be the one the decoder reads it as.
    fn read_expected(
        &mut self,
        kind: Kind,
        id: i64,
        ty: u8,
        e: Expect,
        depth: usize,
    ) -> Result<(), String> {
        let ok = match e {
            Expect::Varint => matches!(ty, I16 | I32 | I64),
            Expect::Binary => ty == BINARY,
            Expect::Byte => ty == BYTE,
            Expect::Bool => matches!(ty, BOOL_TRUE | BOOL_FALSE),
            Expect::Struct(_) => ty == STRUCT,
            Expect::ListVarint | Expect::ListBinary | Expect::ListStruct(_) => {
                matches!(ty, LIST | SET)
            }
        };
        if !ok {
            return Err(format!(
                "footer field {id} of {kind:?} has wire type {ty}, not the {e:?} it holds"
            ));
        }
        match e {
            Expect::Struct(k) => self.skip_struct(k, depth + 1),
            Expect::ListVarint | Expect::ListBinary | Expect::ListStruct(_) => {
                let (elem, size) = self.list_header()?;
                // the decoder takes the size as an i32 (negative: empty)
                let size = self.check_size((size as i32).max(0) as u64, 1, "list")?;
                if size == 0 {
                    return Ok(());
                }
                let elem_ok = match e {
                    Expect::ListVarint => matches!(elem, I16 | I32 | I64),
                    Expect::ListBinary => elem == BINARY,
                    _ => elem == STRUCT,
                };
                if !elem_ok {
                    return Err(format!(
                        "footer list {id} of {kind:?} holds wire type {elem}, not {e:?}"
                    ));
                }
                for _ in 0..size {
                    match e {
                        Expect::ListStruct(k) => self.skip_struct(k, depth + 1)?,
                        _ => self.skip_value(elem, depth + 1, true)?,
                    }
                }
                Ok(())
            }
            _ => self.skip_value(ty, depth, false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file around a footer.
    fn file(footer: &[u8]) -> Vec<u8> {
        let mut f = b"PAR1".to_vec();
        f.extend_from_slice(footer);
        f.extend_from_slice(&(footer.len() as u32).to_le_bytes());
        f.extend_from_slice(b"PAR1");
        f
    }

    #[test]
    fn well_formed_footers_pass() {
        // version (1, i32) = 1, schema (2) a list of 1 empty struct, num_rows (3, i64) = 0,
        // created_by (6, binary) "ab", an unknown field 9 (bool), stop
        let f = file(&[
            0x15, 0x02, 0x19, 0x1c, 0x00, 0x16, 0x00, 0x38, 0x02, b'a', b'b', 0x31, 0x00,
        ]);
        assert_eq!(check_str(&f), Ok(()));
    }

    #[test]
    fn oversized_lists_binaries_and_lengths_are_refused() {
        // a list of row groups (4) claiming 2^31 - 1 structs in a few bytes
        let f = file(&[0x49, 0xfc, 0xff, 0xff, 0xff, 0xff, 0x07, 0x00]);
        assert!(check_str(&f).unwrap_err().contains("list of 2147483647"));
        // created_by (6): a binary of 1000 bytes with 1 left
        let f = file(&[0x68, 0xe8, 0x07, 0x00]);
        assert!(check_str(&f).unwrap_err().contains("binary of 1000"));
        // row groups (4) with an i32 wire type: the decoder would read a list header from
        // the varint's bytes
        let f = file(&[0x45, 0x02, 0x00]);
        assert!(check_str(&f).unwrap_err().contains("wire type 5"));
        // footer length beyond the file
        let mut f = file(&[0x00]);
        let n = f.len();
        f[n - 8..n - 4].copy_from_slice(&1000u32.to_le_bytes());
        assert!(check_str(&f).unwrap_err().contains("footer length 1000"));
        // truncated and unknown types
        assert!(check_str(&file(&[0x15])).unwrap_err().contains("truncated"));
        assert!(check_str(&file(&[0x9e, 0x00]))
            .unwrap_err()
            .contains("unknown type 14"));
        assert!(check_str(b"PAR1PAR1").is_err());
    }

    #[test]
    fn the_decoders_readings_are_followed() {
        // an unknown field 8 holding a list of 8 booleans (the decoder's skipper reads no
        // bytes for them, then a row-group list of 2^31 - 1 from what follows)
        let f = file(&[
            0x89, 0x81, 0x09, 0x08, 0xfc, 0xff, 0xff, 0xff, 0xff, 0x07, 0x00,
        ]);
        assert!(check_str(&f).unwrap_err().to_string().contains("booleans"));
        // a long-form id 0x1FFF7 is field 4 (row groups) to the decoder: its i32 wire type
        // is refused
        let f = file(&[0x05, 0xf7, 0xff, 0x07, 0x02, 0x00]);
        assert!(check_str(&f).unwrap_err().to_string().contains("field 4"));
        // a schema of 100 elements each the only child of the one before
        let mut footer = vec![0x29, 0xfc, 100];
        for _ in 0..100 {
            footer.extend([0x55, 0x02, 0x00]); // num_children (5) = 1
        }
        footer.push(0x00);
        let e = check_str(&file(&footer)).unwrap_err();
        assert!(e.contains("schema nested"), "{e}");
    }

    #[test]
    fn deep_nesting_is_refused() {
        // an unknown struct field (9) holding structs 100 deep
        let mut footer = vec![0x9c];
        footer.extend(vec![0x1c; 99]);
        footer.extend(vec![0x00; 101]);
        assert!(check_str(&file(&footer))
            .unwrap_err()
            .to_string()
            .contains("deeper"));
    }
}
