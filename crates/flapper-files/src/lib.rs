//! The one way flapper writes an output file: complete or absent, never half written. Every crate
//! that writes files (learner checkpoints, plots, evaluation CSVs, the report) goes through it.
//! [`write_csv_rows`] and [`write_csv_records`] write a CSV file of `Serialize` rows that way; [`decimals`] prints a row's
//! numbers at the precision its file keeps. [`write_json`] writes JSON, [`read_json`] reads it back as the type that
//! wrote it ([`nan_as_null`] for numbers that may be NaN).

use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to a temporary file beside `path`, flushes it to disk, then renames it over `path`:
/// a reader (or a crash, or a full disk) sees the old file or the new one, never part of one. On any
/// failure the temporary file is removed and `path` keeps what it held.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(format!(".tmp-{}", std::process::id()));
    let temporary = PathBuf::from(temporary);
    let written =
        std::fs::File::create(&temporary).and_then(|mut file| file.write_all(bytes).and_then(|()| file.sync_all()));
    let result = written.and_then(|()| std::fs::rename(&temporary, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result
}

/// Writes `value` to `path` as pretty-printed JSON, whole or not at all: every JSON file flapper writes.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> std::io::Result<()> {
    write_atomically(path, serde_json::to_string_pretty(value).map_err(std::io::Error::from)?.as_bytes())
}

/// A folder's lock: `dir/.lock`, held until the returned file is dropped (the OS releases it when the
/// process ends, however it ends). `Ok(None)` when another process holds it.
pub fn lock_folder(dir: &Path) -> std::io::Result<Option<std::fs::File>> {
    let file = std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(dir.join(".lock"))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(file)),
        Err(std::fs::TryLockError::WouldBlock) => Ok(None),
        Err(std::fs::TryLockError::Error(e)) => Err(e),
    }
}

/// Writes `header`, then one record per row, to `path` as CSV, whole or not at all. A row's field may
/// hold several columns (an array: each joint's angle), which is why the header is given, not derived.
pub fn write_csv_rows<R: serde::Serialize>(
    path: &Path,
    header: &[String],
    rows: impl IntoIterator<Item = R>,
) -> csv::Result<()> {
    write_csv(path, Some(header), rows)
}

/// Writes rows of a flat `Serialize` struct to `path` as CSV, whole or not at all, under a header of
/// the struct's field names (no rows, an empty file).
pub fn write_csv_records<R: serde::Serialize>(path: &Path, rows: impl IntoIterator<Item = R>) -> csv::Result<()> {
    write_csv(path, None, rows)
}

fn write_csv<R: serde::Serialize>(
    path: &Path,
    header: Option<&[String]>,
    rows: impl IntoIterator<Item = R>,
) -> csv::Result<()> {
    let mut out = csv::WriterBuilder::new().has_headers(header.is_none()).from_writer(Vec::new());
    if let Some(header) = header {
        out.write_record(header)?;
    }
    for row in rows {
        out.serialize(row)?;
    }
    let bytes = out.into_inner().map_err(|e| e.into_error())?;
    Ok(write_atomically(path, &bytes)?)
}

/// `serialize_with` helpers for `Serialize` CSV rows: a number, or each of several, at `DECIMALS`
/// decimals (`#[serde(serialize_with = "flapper_files::decimals::fixed::<3, _>")]`). A row with
/// several numbers in one field has its header written by hand beside it (the csv crate names only
/// single-value fields).
pub mod decimals {
    use serde::Serializer;

    pub fn fixed<const DECIMALS: usize, S: Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(&format_args!("{value:.DECIMALS$}"))
    }

    pub fn each_fixed<const DECIMALS: usize, S: Serializer>(values: &[f64], serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(values.iter().map(|v| format!("{v:.DECIMALS$}")))
    }

    /// A number that may be missing: empty in a CSV file (which reads back as `None`).
    pub fn optional_fixed<const DECIMALS: usize, S: Serializer>(
        value: &Option<f64>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        match value {
            Some(value) => fixed::<DECIMALS, S>(value, serializer),
            None => serializer.serialize_none(),
        }
    }
}

/// Reads back a JSON file that [`write_json`] wrote, as the type that wrote it; the error says what went
/// wrong (the caller names the file).
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    serde_json::from_str(&text).map_err(|e| e.to_string())
}

/// `deserialize_with` helpers for numbers that may be NaN. JSON has no NaN: serde_json writes NaN (and
/// the infinities) as `null`, and then refuses `null` for an `f64`. A result field that can be NaN
/// ("no episode completed", "the joint does not move") reads `null` back as NaN with
/// `#[serde(deserialize_with = "flapper_files::nan_as_null::number")]` (or `::numbers` for an array).
pub mod nan_as_null {
    use serde::{Deserialize, Deserializer};

    pub fn number<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(deserializer)?.unwrap_or(f64::NAN))
    }

    pub fn numbers<'de, D: Deserializer<'de>, const N: usize>(deserializer: D) -> Result<[f64; N], D::Error> {
        let values = Vec::<Option<f64>>::deserialize(deserializer)?;
        let count = values.len();
        let numbers: Vec<f64> = values.into_iter().map(|v| v.unwrap_or(f64::NAN)).collect();
        numbers.try_into().map_err(|_| serde::de::Error::invalid_length(count, &format!("{N} numbers").as_str()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_written_as_null_reads_back_as_nan() {
        #[derive(serde::Serialize, serde::Deserialize)]
        struct Figures {
            #[serde(deserialize_with = "nan_as_null::number")]
            x: f64,
            #[serde(deserialize_with = "nan_as_null::numbers")]
            each: [f64; 3],
        }
        let text = serde_json::to_string(&Figures { x: f64::NAN, each: [1.5, f64::NAN, 2.0] }).unwrap();
        assert_eq!(text, r#"{"x":null,"each":[1.5,null,2.0]}"#);
        let back: Figures = serde_json::from_str(&text).unwrap();
        assert!(back.x.is_nan() && back.each[1].is_nan());
        assert_eq!((back.each[0], back.each[2]), (1.5, 2.0));
        assert!(serde_json::from_str::<Figures>(r#"{"x":1.0,"each":[1.0,2.0]}"#).is_err(), "two numbers for three");
    }

    #[test]
    fn a_row_prints_each_number_at_its_decimals() {
        #[derive(serde::Serialize)]
        struct Row {
            n: usize,
            #[serde(serialize_with = "decimals::fixed::<2, _>")]
            x: f64,
            #[serde(serialize_with = "decimals::each_fixed::<1, _>")]
            v: [f64; 3],
        }
        let mut writer = csv::WriterBuilder::new().has_headers(false).from_writer(Vec::new());
        writer.serialize(Row { n: 7, x: 1.0 / 3.0, v: [0.04, -2.25, 10.0] }).unwrap();
        assert_eq!(String::from_utf8(writer.into_inner().unwrap()).unwrap(), "7,0.33,0.0,-2.2,10.0\n");
    }

    #[test]
    fn replaces_whole_or_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("flapper-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("out.csv");
        write_atomically(&file, b"old").unwrap();
        write_atomically(&file, b"new").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"new");
        // A folder in the way: the write fails, nothing is left behind.
        let blocked = dir.join("blocked");
        std::fs::create_dir_all(blocked.join("inside")).unwrap();
        assert!(write_atomically(&blocked, b"x").is_err());
        let names: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
