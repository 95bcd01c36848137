//! Parquet/CSV table helpers over polars' eager API: atomic writes with file-level key-value
//! metadata, streaming (batched, one row group per batch) writers, column extraction with
//! errors that name the file and column.
//!
//! Every Parquet read goes through [`guarded`]: polars returns errors for most corrupt
//! files but panics on some (bad page headers, dictionary indices out of range, columns
//! whose lengths disagree). A panic inside the reader is caught there and becomes one
//! `Error::Table` line naming the file; while a guarded read runs, the panic hook stays
//! silent so the caught panic prints nothing. The frame read is then checked up front
//! ([`check_frame`]: every column as long as the frame) before any column is indexed.

mod footer;

use crate::error::{Error, Result};
use crate::io::OutputFile;
use polars::prelude::*;
use std::fs::File;
use std::path::{Path, PathBuf};

/// Build a column from a vector.
pub fn col<T>(name: &str, v: Vec<T>) -> Column
where
    Series: NamedFrom<Vec<T>, [T]>,
{
    Column::new(name.into(), v)
}

/// Build a frame from equal-length columns.
pub fn frame(path: &Path, cols: Vec<Column>) -> Result<DataFrame> {
    let h = cols.first().map(|c| c.len()).unwrap_or(0);
    DataFrame::new(h, cols).map_err(|e| Error::table(path, e))
}

/// A streaming Parquet writer: every frame written becomes row groups (one per chunk) as
/// it comes; the file-level key-value metadata may be set at any time before
/// [`ParquetStream::finish`], which writes the footer and renames the temp file into place
/// (through [`OutputFile`]: a device or FIFO output is written straight into).
///
/// Written over polars-parquet's `FileWriter` rather than polars' `BatchedWriter`, whose
/// metadata is fixed when the first batch is written: a stage that learns its metadata
/// only at the end (the energy stage's N0) can then stream its rows. The file is what
/// polars' writer makes (statistics, Snappy pages, the Arrow schema first in the
/// metadata), except that floating-point columns are written plain, not dictionary-encoded.
pub struct ParquetStream {
    path: PathBuf,
    /// The output, opened with the first frame (dropped unfinished: its temp is removed).
    out: Option<OutputFile>,
    writer: Option<StreamWriter>,
    meta: Vec<(String, String)>,
}

/// The open file of a [`ParquetStream`].
struct StreamWriter {
    file: polars_parquet::write::FileWriter<std::io::BufWriter<File>>,
    encodings: polars_buffer::Buffer<Vec<polars_parquet::write::Encoding>>,
    fields: Vec<polars_parquet::write::ParquetType>,
    options: polars_parquet::write::WriteOptions,
    /// The first frame's schema: every later frame must have it.
    schema: Schema,
}

impl ParquetStream {
    /// Start writing `path`.
    pub fn create(path: &Path) -> Result<Self> {
        // refused now (a directory or socket), before any work is done for it
        crate::io::destination(path)?;
        Ok(ParquetStream {
            path: path.to_path_buf(),
            out: None,
            writer: None,
            meta: Vec::new(),
        })
    }

    /// Set the file-level key-value metadata (any time before [`ParquetStream::finish`]).
    pub fn set_metadata(&mut self, kv: Vec<(String, String)>) {
        self.meta = kv;
    }

    /// Append one frame (one row group per chunk of the frame).
    pub fn write(&mut self, df: &DataFrame) -> Result<()> {
        use polars_parquet::write as pw;
        let path = self.path.clone();
        let terr = |e: PolarsError| Error::table(&path, e);
        if self.writer.is_none() {
            let (out, file) = OutputFile::create(&self.path)?;
            self.out = Some(out);
            let schema = df.schema().to_arrow(CompatLevel::newest());
            // floating-point columns plain: measured values (energies, positions) are
            // nearly all distinct, and polars' dictionary attempt (a cardinality estimate
            // over every value, then a fallback) was most of the energy stage's write time
            let encodings = schema
                .iter_values()
                .map(|f| match f.dtype {
                    ArrowDataType::Float64 | ArrowDataType::Float32 => {
                        vec![pw::Encoding::Plain]
                    }
                    _ => pw::get_dtype_encoding(&f.dtype),
                })
                .collect();
            let options = pw::WriteOptions {
                statistics: pw::StatisticsOptions::default(),
                compression: pw::CompressionOptions::Snappy,
                version: pw::Version::V1,
                data_page_size: None,
            };
            let file = pw::FileWriter::try_new(file, schema, options).map_err(terr)?;
            let fields = file.parquet_schema().fields().to_vec();
            self.writer = Some(StreamWriter {
                file,
                encodings,
                fields,
                options,
                schema: df.schema().as_ref().clone(),
            });
        }
        let w = self.writer.as_mut().expect("writer");
        if df.schema().as_ref() != &w.schema {
            return Err(Error::table(
                &self.path,
                "a batch's columns differ from the first batch's (internal error)",
            ));
        }
        for batch in df.iter_chunks(CompatLevel::newest(), false) {
            let rows = batch.len();
            if rows == 0 {
                continue;
            }
            let rg = pw::row_group_iter(batch, w.encodings.clone(), w.fields.clone(), w.options);
            w.file.write(rows as u64, rg).map_err(terr)?;
        }
        Ok(())
    }

    /// Finish the file and rename it into place. `empty` is written when no frame was
    /// (the file then has the schema and zero rows).
    pub fn finish(mut self, empty: Option<&DataFrame>) -> Result<()> {
        use polars_parquet::write as pw;
        if self.writer.is_none() {
            if let Some(df) = empty {
                self.write(df)?;
            } else {
                return Err(Error::input(&self.path, "no rows to write"));
            }
        }
        let mut w = self.writer.take().expect("writer");
        let mut kv = vec![pw::schema_to_metadata_key(w.file.schema())];
        kv.extend(self.meta.drain(..).map(|(key, value)| pw::KeyValue {
            key,
            value: Some(value),
        }));
        w.file
            .end(Some(kv))
            .map_err(|e| Error::table(&self.path, e))?;
        let out = self.out.take().expect("opened with the writer");
        out.commit(w.file.into_inner())
    }
}

/// Write a whole frame atomically with metadata.
pub fn write_parquet(path: &Path, df: &DataFrame, meta: Vec<(String, String)>) -> Result<()> {
    let mut s = ParquetStream::create(path)?;
    s.set_metadata(meta);
    s.write(df)?;
    s.finish(None)
}

/// Write a frame as CSV atomically.
pub fn write_csv(path: &Path, df: &mut DataFrame) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        CsvWriter::new(w)
            .include_header(true)
            .finish(df)
            .map_err(|e| Error::table(path, e))
    })
}

fn open(path: &Path) -> Result<File> {
    File::open(path).map_err(|e| Error::io(path, e))
}

/// Open a Parquet file whose footer [`footer::check`] finds well formed (list and binary
/// sizes within the footer's bytes): polars' footer decoder pre-sizes its vectors from
/// those counts, and a corrupt one aborts the process on allocation.
fn open_parquet(path: &Path) -> Result<File> {
    let file = open(path)?;
    check_footer(path, &file)?;
    Ok(file)
}

/// [`footer::check`] on an open file (`path` names it in the error).
fn check_footer(path: &Path, file: &File) -> Result<()> {
    // SAFETY: a read-only map of a file this run only reads (see `check_pages`).
    let map = unsafe { memmap2::Mmap::map(file) }.map_err(|e| Error::io(path, e))?;
    footer::check(&map).map_err(|m| Error::table(path, format!("corrupt Parquet file ({m})")))
}

/// Open a Parquet file for several reads: its footer ([`footer::check`]) and pages
/// ([`check_pages`]) checked once. The reads that follow go through this handle (clones
/// of it), so a file renamed over the path meanwhile — how pradar's writers replace
/// outputs — is never read with the first file's footer.
/// Gives the file and its parsed footer (the one the page check walked).
pub fn open_checked(path: &Path) -> Result<(File, FileMetadataRef)> {
    let file = open(path)?;
    check_footer(path, &file)?;
    let md = check_pages_file(path, &file)?;
    Ok((file, md))
}

/// Guarded reads in progress (the panic hook is silent while this is above 0).
static GUARDED_READS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
static QUIET_HOOK: std::sync::Once = std::sync::Once::new();

/// Run a polars read of `path`, turning its error or its panic into one error naming the
/// file. The first call wraps the process's panic hook so that it prints nothing while a
/// guarded read is in progress (on any thread: polars reads on its own pool); a panic
/// elsewhere during that time still unwinds as before, only unprinted.
pub fn guarded<T>(path: &Path, read: impl FnOnce() -> PolarsResult<T>) -> Result<T> {
    use std::sync::atomic::Ordering;
    QUIET_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if GUARDED_READS.load(Ordering::SeqCst) == 0 {
                previous(info)
            }
        }));
    });
    GUARDED_READS.fetch_add(1, Ordering::SeqCst);
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read));
    GUARDED_READS.fetch_sub(1, Ordering::SeqCst);
    match r {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(Error::table(path, e)),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown failure".into());
            Err(Error::table(
                path,
                format!(
                    "corrupt Parquet file (the reader failed: {})",
                    what.replace('\n', " ")
                ),
            ))
        }
    }
}

/// Every column of a frame read from `path` is as long as the frame (a corrupt file can
/// give columns of different lengths).
pub fn check_frame(path: &Path, df: &DataFrame) -> Result<()> {
    let h = df.height();
    for c in df.columns() {
        if c.len() != h {
            return Err(Error::input(
                path,
                format!(
                    "column `{}` has {} values but the table {h} rows (corrupt file?)",
                    c.name(),
                    c.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Most rows a row group may claim: 2^27, so a column's decode buffer stays within 1 GiB
/// (pradar writes at most 2^20; pyarrow's default is 2^20, polars' 2^18).
pub const MAX_GROUP_ROWS: usize = 1 << 27;

/// Largest ratio of a page's uncompressed to compressed size accepted (zstd and LZ4 reach
/// a few hundred on constant data; a corrupt header claims billions).
const MAX_PAGE_EXPANSION: usize = 4096;

/// Walk every page header of a Parquet file (memory-mapped: nothing is decoded or copied)
/// and refuse counts the decoder would trust for its allocations: a data page's
/// `num_values` above its row group's row count (a negative count reads as about 2^64 and
/// made polars abort on a 2^61-byte allocation), an uncompressed size more than
/// [`MAX_PAGE_EXPANSION`] times the compressed one, a column whose pages' counts do not
/// add up to its row group's rows, or a row group of more than [`MAX_GROUP_ROWS`] rows.
/// Such an allocation failure aborts the process, which [`guarded`] cannot catch; this
/// check runs before it.
pub fn check_pages(path: &Path) -> Result<()> {
    let file = open_parquet(path)?;
    check_pages_file(path, &file).map(|_| ())
}

/// [`check_pages`] on an open file whose footer has been checked; gives the parsed footer.
fn check_pages_file(path: &Path, file: &File) -> Result<FileMetadataRef> {
    use polars_parquet::parquet::page::CompressedPage;
    use polars_parquet::parquet::read::{get_page_iterator, read_metadata};
    use std::io::Cursor;
    // SAFETY: a read-only map of a file this run only reads; a file truncated by another
    // process meanwhile is outside what any reader can defend against.
    let map = unsafe { memmap2::Mmap::map(file) }.map_err(|e| Error::io(path, e))?;
    let size = map.len();
    let buf = polars_buffer::Buffer::from_owner(map);
    let bad = |msg: String| Error::table(path, format!("corrupt Parquet file ({msg})"));
    let md = guarded(path, || {
        read_metadata(&mut Cursor::new(buf.clone())).map_err(PolarsError::from)
    })?;
    drop(buf);
    for (g, rg) in md.row_groups.iter().enumerate() {
        let rows = rg.num_rows();
        // the decoders size their buffers from the claimed row count
        if rows > MAX_GROUP_ROWS {
            return Err(bad(format!(
                "row group {g} claims {rows} rows (at most {MAX_GROUP_ROWS} are read)"
            )));
        }
        // a fresh map per row group: the pages read through it leave the process's resident
        // set when it is dropped, so the check's memory does not grow with the file
        // SAFETY: as above.
        let map = unsafe { memmap2::Mmap::map(file) }.map_err(|e| Error::io(path, e))?;
        let buf = polars_buffer::Buffer::from_owner(map);
        for (c, col) in rg.parquet_columns().iter().enumerate() {
            let pages = guarded(path, || {
                get_page_iterator(col, Cursor::new(buf.clone()), Vec::new(), size)
                    .map_err(PolarsError::from)
            })?;
            let mut values = 0usize;
            for page in pages {
                let page = page.map_err(|e| Error::table(path, PolarsError::from(e)))?;
                // (a dictionary page's sizes are not exposed by polars-parquet: unchecked)
                let CompressedPage::Data(p) = &page else {
                    continue;
                };
                let (n, compressed, uncompressed) =
                    (p.num_values(), p.compressed_size(), p.uncompressed_size());
                if n > rows {
                    return Err(bad(format!(
                        "row group {g} column {c}: a page of {n} values in a group of {rows} rows"
                    )));
                }
                if uncompressed > compressed.max(1).saturating_mul(MAX_PAGE_EXPANSION) {
                    return Err(bad(format!(
                        "row group {g} column {c}: a page of {compressed} bytes claims {uncompressed} uncompressed"
                    )));
                }
                values = values.saturating_add(n);
            }
            // a flat column holds one value (or null) per row: the pages' counts add up to
            // the group's, so a group cannot claim rows its pages do not hold
            if values != rows {
                return Err(bad(format!(
                    "row group {g} column {c}: pages hold {values} values for {rows} rows"
                )));
            }
        }
    }
    Ok(std::sync::Arc::new(md))
}

/// Read a Parquet file (optionally a row slice `(offset, len)`), guarded and checked
/// ([`check_pages`] first).
pub fn read_parquet(path: &Path, slice: Option<(usize, usize)>) -> Result<DataFrame> {
    check_pages(path)?;
    let file = open(path)?;
    let df =
        guarded(path, || ParquetReader::new(file).with_slice(slice).finish()).map_err(|e| {
            // the schema read again only to name a column the reader could not load
            let schema = open(path)
                .ok()
                .and_then(|f| guarded(path, || ParquetReader::new(f).schema()).ok());
            match schema {
                Some(schema) => unreadable_column(path, &schema, e),
                None => e,
            }
        })?;
    check_frame(path, &df)?;
    Ok(df)
}

/// The Parquet metadata (footer) of a file, parsed once for [`read_parquet_part`].
pub type FileMetadataRef = std::sync::Arc<polars_parquet::read::FileMetadata>;

/// Parse the footer of a Parquet file (guarded).
pub fn parquet_file_metadata(path: &Path) -> Result<FileMetadataRef> {
    let file = open_parquet(path)?;
    guarded(path, || {
        let mut r = ParquetReader::new(file);
        r.get_metadata().cloned()
    })
}

/// The file-level key-value metadata held in a parsed footer.
pub fn key_values(md: &FileMetadataRef) -> Vec<(String, String)> {
    md.key_value_metadata
        .as_ref()
        .map(|kv| {
            kv.iter()
                .map(|k| (k.key.clone(), k.value.clone().unwrap_or_default()))
                .collect()
        })
        .unwrap_or_default()
}

/// Read the rows `slice = (offset, len)` of the columns `columns` of a file and its footer
/// `md` from [`open_checked`]: only the row groups overlapping the
/// slice are decoded. A missing column is named (`path` names the file).
pub fn read_parquet_part(
    path: &Path,
    file: &File,
    md: &FileMetadataRef,
    slice: (usize, usize),
    columns: &[&str],
) -> Result<DataFrame> {
    let file = file.try_clone().map_err(|e| Error::io(path, e))?;
    let mut r = ParquetReader::new(file);
    r.set_metadata(md.clone());
    let schema = guarded(path, || r.schema())?;
    for c in columns {
        if schema.get(c).is_none() {
            return Err(Error::input(path, format!("missing column `{c}`")));
        }
    }
    let cols = columns.iter().map(|c| c.to_string()).collect();
    let df = guarded(path, || {
        r.with_columns(Some(cols)).with_slice(Some(slice)).finish()
    })
    .map_err(|e| unreadable_column(path, &schema, e))?;
    check_frame(path, &df)?;
    Ok(df)
}

/// A read error of `path` made plain when it is polars' "cannot create series from
/// <type>" (a column whose Arrow type this build of polars does not load, such as Int8):
/// the column named, with its type and the types read instead (from the file's `schema`).
/// Any other error is returned as it is. (The Parquet reader of this build reads an Int8,
/// Int16 or Date column as its physical Int32, so such a file is read, not refused.)
fn unreadable_column(path: &Path, schema: &ArrowSchema, e: Error) -> Error {
    let Error::Table { msg, .. } = &e else {
        return e;
    };
    let Some(dtype) = msg
        .split("cannot create series from ")
        .nth(1)
        .map(str::trim)
    else {
        return e;
    };
    let Some(field) = schema
        .iter_values()
        .find(|f| format!("{:?}", f.dtype) == dtype)
    else {
        return e;
    };
    let expected = if dtype.starts_with("Int") || dtype.starts_with("UInt") {
        "Int32, Int64, UInt32 or UInt64"
    } else if dtype.starts_with("Float") {
        "Float32 or Float64"
    } else {
        "Int32, Int64, UInt32, UInt64, Float32, Float64 or String"
    };
    Error::input(
        path,
        format!(
            "column `{}` is {dtype}, a type pradar does not read (expected {expected})",
            field.name
        ),
    )
}

/// Number of rows of a Parquet file.
pub fn parquet_rows(path: &Path) -> Result<usize> {
    let file = open_parquet(path)?;
    guarded(path, || ParquetReader::new(file).num_rows())
}

/// File-level key-value metadata of a Parquet file.
pub fn parquet_metadata(path: &Path) -> Result<Vec<(String, String)>> {
    let file = open_parquet(path)?;
    guarded(path, || {
        let mut r = ParquetReader::new(file);
        let md = r.get_metadata()?;
        Ok(md
            .key_value_metadata
            .as_ref()
            .map(|kv| {
                kv.iter()
                    .map(|k| (k.key.clone(), k.value.clone().unwrap_or_default()))
                    .collect()
            })
            .unwrap_or_default())
    })
}

/// A required f64 column without nulls or non-finite values.
pub fn f64_column(path: &Path, df: &DataFrame, name: &str) -> Result<Vec<f64>> {
    f64_values(path, df, name, |x| {
        (!x.is_finite()).then(|| format!("non-finite value {x}"))
    })
}

/// A power column in dB: finite values or −∞ (a path of zero power, as `simulate`'s truth
/// writes a scatterer of zero σ); NaN, +∞ and nulls are errors (rows counted in `df`).
pub fn db_column(path: &Path, df: &DataFrame, name: &str) -> Result<Vec<f64>> {
    f64_values(path, df, name, |x| {
        (!(x.is_finite() || x == f64::NEG_INFINITY)).then(|| format!("{x} is not a power in dB"))
    })
}

/// A required column cast to f64, without nulls; `reject` says why a value is refused
/// (`None`: kept), each error naming the file, column and row.
fn f64_values(
    path: &Path,
    df: &DataFrame,
    name: &str,
    reject: impl Fn(f64) -> Option<String>,
) -> Result<Vec<f64>> {
    let c = df
        .column(name)
        .map_err(|_| Error::input(path, format!("missing column `{name}`")))?;
    let c = c
        .cast(&DataType::Float64)
        .map_err(|_| Error::input(path, format!("column `{name}` is not numeric")))?;
    let ca = c.f64().map_err(|e| Error::table(path, e))?;
    ca.iter()
        .enumerate()
        .map(|(i, v)| match v {
            Some(x) => match reject(x) {
                None => Ok(x),
                Some(why) => Err(Error::input(
                    path,
                    format!("column `{name}` row {i}: {why}"),
                )),
            },
            None => Err(Error::input(path, format!("column `{name}` row {i}: null"))),
        })
        .collect()
}

/// An f64 column whose NaN (or null) cells mean "no value" (a sweep a campaign does not
/// have); the caller decides where that is allowed. Infinite values are an error.
pub fn f64_column_nan(path: &Path, df: &DataFrame, name: &str) -> Result<Vec<f64>> {
    f64_column_or_nan(path, df, name)?
        .ok_or_else(|| Error::input(path, format!("missing column `{name}`")))
}

/// An optional f64 column whose NaN cells mean "not applicable" (nulls read as NaN too);
/// `Ok(None)` when the table has no such column. Infinite values are an error.
pub fn f64_column_or_nan(path: &Path, df: &DataFrame, name: &str) -> Result<Option<Vec<f64>>> {
    let Ok(c) = df.column(name) else {
        return Ok(None);
    };
    let c = c
        .cast(&DataType::Float64)
        .map_err(|_| Error::input(path, format!("column `{name}` is not numeric")))?;
    let ca = c.f64().map_err(|e| Error::table(path, e))?;
    ca.iter()
        .enumerate()
        .map(|(i, v)| match v {
            Some(x) if x.is_infinite() => Err(Error::input(
                path,
                format!("column `{name}` row {i}: infinite value {x}"),
            )),
            Some(x) => Ok(x),
            None => Ok(f64::NAN),
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// A string column without nulls; `Ok(None)` when the table has no such column.
pub fn str_column(path: &Path, df: &DataFrame, name: &str) -> Result<Option<Vec<String>>> {
    let Ok(c) = df.column(name) else {
        return Ok(None);
    };
    let c = c
        .cast(&DataType::String)
        .map_err(|_| Error::input(path, format!("column `{name}` is not text")))?;
    let ca = c.str().map_err(|e| Error::table(path, e))?;
    ca.iter()
        .enumerate()
        .map(|(i, v)| {
            v.map(str::to_string)
                .ok_or_else(|| Error::input(path, format!("column `{name}` row {i}: null")))
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// A required integer column (cast to i64) without nulls.
pub fn i64_column(path: &Path, df: &DataFrame, name: &str) -> Result<Vec<i64>> {
    let c = df
        .column(name)
        .map_err(|_| Error::input(path, format!("missing column `{name}`")))?;
    let c = c
        .cast(&DataType::Int64)
        .map_err(|_| Error::input(path, format!("column `{name}` is not an integer")))?;
    let ca = c.i64().map_err(|e| Error::table(path, e))?;
    ca.iter()
        .enumerate()
        .map(|(i, v)| v.ok_or_else(|| Error::input(path, format!("column `{name}` row {i}: null"))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_polars_cannot_load_is_named() {
        let schema: ArrowSchema = [
            ArrowField::new("bin".into(), ArrowDataType::Int32, false),
            ArrowField::new("position".into(), ArrowDataType::Int8, false),
        ]
        .into_iter()
        .collect();
        let p = Path::new("e.parquet");
        let e = unreadable_column(
            p,
            &schema,
            Error::table(p, "cannot create series from Int8"),
        );
        assert_eq!(
            e.to_string(),
            "e.parquet: column `position` is Int8, a type pradar does not read (expected Int32, Int64, UInt32 or UInt64)"
        );
        // any other error stands as it is
        let e = unreadable_column(p, &schema, Error::table(p, "out of spec"));
        assert_eq!(e.to_string(), "e.parquet: table error: out of spec");
    }
}
