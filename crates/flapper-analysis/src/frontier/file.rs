//! `frontier.csv`: one [`FrontierRow`] per controller, written and read back here (the rows a run
//! measured, and points measured elsewhere, `docs/energy-frontier.csv`, in the same columns).

use std::path::Path;

use super::{COLUMNS, FrontierRow};
use crate::AnalysisError;

/// The file a frontier run writes.
pub const FRONTIER_CSV: &str = "frontier.csv";

/// Writes `rows` to `path` under [`COLUMNS`], whole or not at all.
pub fn write_frontier_csv<'a>(
    path: &Path,
    rows: impl IntoIterator<Item = &'a FrontierRow>,
) -> Result<(), AnalysisError> {
    flapper_files::write_csv_records(path, rows)
        .map_err(|e| AnalysisError::Write { path: path.to_owned(), message: e.to_string() })
}

/// Reads rows in [`COLUMNS`] (any order; a missing column other than `label` and `source` reads as
/// missing figures): an empty field is a missing figure. Refuses, naming the file and the line, an
/// unknown column, a field that is not a number, a negative or non-finite number, more episodes
/// completed than flown, a glide fraction outside 0-1, and a row without a label or a source.
pub fn read_frontier_csv(path: &Path) -> Result<Vec<FrontierRow>, AnalysisError> {
    let fail = |line: u64, message: String| AnalysisError::FrontierFile { path: path.to_owned(), line, message };
    let mut reader = csv::ReaderBuilder::new()
        .from_path(path)
        .map_err(|e| AnalysisError::Read { path: path.to_owned(), message: e.to_string() })?;
    let headers = reader.headers().map_err(|e| fail(1, e.to_string()))?.clone();
    if let Some(unknown) = headers.iter().find(|column| !COLUMNS.contains(column)) {
        return Err(fail(1, format!("unknown column '{unknown}' (the columns: {})", COLUMNS.join(","))));
    }
    for required in ["label", "source"] {
        if !headers.iter().any(|column| column == required) {
            return Err(fail(1, format!("no '{required}' column")));
        }
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| fail(line_of(&e), record_error(&e)))?;
        let line = record.position().map_or(0, csv::Position::line);
        let row: FrontierRow = record.deserialize(Some(&headers)).map_err(|e| {
            let column = match e.kind() {
                csv::ErrorKind::Deserialize { err, .. } => err.field().and_then(|k| headers.get(k as usize)),
                _ => None,
            };
            let what = match e.kind() {
                csv::ErrorKind::Deserialize { err, .. } => err.kind().to_string(),
                _ => e.to_string(),
            };
            fail(line, column.map_or(what.clone(), |c| format!("column '{c}': {what}")))
        })?;
        check(&row).map_err(|message| fail(line, message))?;
        rows.push(row);
    }
    Ok(rows)
}

/// The line of a record the csv reader refused (0 where it does not say).
fn line_of(error: &csv::Error) -> u64 {
    error.position().map_or(0, csv::Position::line)
}

fn record_error(error: &csv::Error) -> String {
    match error.kind() {
        csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
            format!("{len} fields where the header has {expected_len}")
        }
        _ => error.to_string(),
    }
}

/// What is wrong with a row read from a file, if anything.
fn check(row: &FrontierRow) -> Result<(), String> {
    if row.label.trim().is_empty() {
        return Err("no label".into());
    }
    if row.source.trim().is_empty() {
        return Err(format!("'{}' has no source (the command that measured it)", row.label));
    }
    let numbers = [
        ("longitudinal_rms_m", row.longitudinal_rms_m),
        ("longitudinal_j_per_m", row.longitudinal_j_per_m),
        ("scripted_j_per_m", row.scripted_j_per_m),
        ("energy_ratio", row.energy_ratio),
        ("glide_fraction", row.glide_fraction),
        ("cruise_flap_hz", row.cruise_flap_hz),
        ("level3_rms_m", row.level3_rms_m),
    ];
    for (column, value) in numbers {
        if let Some(value) = value
            && !(value.is_finite() && value >= 0.0)
        {
            return Err(format!("column '{column}': {value} is not a number of 0 or more"));
        }
    }
    if row.glide_fraction.is_some_and(|fraction| fraction > 1.0) {
        return Err("column 'glide_fraction': a share of the segment, 0 to 1".into());
    }
    let counts = [
        ("longitudinal", row.longitudinal_completed, row.longitudinal_episodes),
        ("level3", row.level3_completed, row.level3_episodes),
    ];
    for (name, completed, episodes) in counts {
        if let (Some(completed), Some(episodes)) = (completed, episodes)
            && completed > episodes
        {
            return Err(format!("{name}_completed {completed} is more than {name}_episodes {episodes}"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("flapper-frontier-file-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn a_row() -> FrontierRow {
        FrontierRow {
            label: "final".into(),
            policy: "policies/final/policy.safetensors".into(),
            longitudinal_completed: Some(100),
            longitudinal_episodes: Some(100),
            longitudinal_rms_m: Some(0.25),
            longitudinal_j_per_m: Some(13.03),
            scripted_j_per_m: Some(2.4),
            energy_ratio: Some(5.43),
            glide_fraction: Some(0.0),
            cruise_flap_hz: None,
            level3_completed: Some(100),
            level3_rms_m: Some(0.705),
            level3_episodes: Some(100),
            source: "flapper frontier --episodes 100 --seed 11".into(),
        }
    }

    #[test]
    fn rows_read_back_as_written_under_the_documented_columns() {
        let path = scratch("round-trip").join(FRONTIER_CSV);
        let rows = vec![a_row(), FrontierRow { label: "scripted gait".into(), source: "s".into(), ..a_row() }];
        write_frontier_csv(&path, &rows).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().next().unwrap(), COLUMNS.join(","));
        assert!(text.contains(",0.2500,13.030,2.400,5.430,0.000,,100,0.7050,100,"), "{text}");
        assert_eq!(read_frontier_csv(&path).unwrap(), rows);
    }

    #[test]
    fn a_malformed_points_file_is_refused_naming_the_file_and_the_line() {
        let dir = scratch("malformed");
        let header = "label,longitudinal_rms_m,energy_ratio,source";
        let cases = [
            (format!("{header}\nA,0.3,1.5,x\nB,0.2,seven,x\n"), "line 3: column 'energy_ratio': "),
            (format!("{header}\nA,0.3,1.5,x\nB,0.2\n"), "line 3: 2 fields where the header has 4"),
            (format!("{header}\nA,-0.3,1.5,x\n"), "line 2: column 'longitudinal_rms_m': -0.3 is not"),
            (format!("{header}\nA,NaN,1.5,x\n"), "line 2: column 'longitudinal_rms_m': NaN is not"),
            (format!("{header}\nA,0.3,1.5,\n"), "line 2: 'A' has no source"),
            (format!("{header}\n,0.3,1.5,x\n"), "line 2: no label"),
            ("label,rms,source\nA,0.3,x\n".to_owned(), "line 1: unknown column 'rms'"),
            ("label,energy_ratio\nA,1.5\n".to_owned(), "line 1: no 'source' column"),
            (
                "label,level3_completed,level3_episodes,source\nA,51,50,x\n".to_owned(),
                "line 2: level3_completed 51 is more than level3_episodes 50",
            ),
        ];
        for (k, (text, expected)) in cases.iter().enumerate() {
            let path = dir.join(format!("points-{k}.csv"));
            std::fs::write(&path, text).unwrap();
            let message = read_frontier_csv(&path).unwrap_err().to_string();
            assert!(message.starts_with(&format!("'{}' ", path.display())), "{message}");
            assert!(message.contains(expected), "{expected:?} not in: {message}");
        }
        let missing = dir.join("nowhere.csv");
        assert!(read_frontier_csv(&missing).unwrap_err().to_string().contains(&missing.display().to_string()));
    }

    #[test]
    fn empty_fields_are_missing_figures_and_columns_may_be_left_out() {
        let path = scratch("sparse").join("points.csv");
        std::fs::write(&path, "source,label,longitudinal_rms_m,energy_ratio,glide_fraction\nx,EN3,0.620,2.55,\n")
            .unwrap();
        let rows = read_frontier_csv(&path).unwrap();
        let expected = FrontierRow {
            label: "EN3".into(),
            longitudinal_rms_m: Some(0.62),
            energy_ratio: Some(2.55),
            source: "x".into(),
            ..FrontierRow::default()
        };
        assert_eq!(rows, [expected]);
    }
}
