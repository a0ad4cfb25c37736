//! A user's own reference: a CSV whose header names the columns `time_s`, `x_m`, `y_m` and `z_m`, in any
//! order (read by name; a missing or unknown column is refused by name). It is checked, then resampled to
//! the control rate.

use std::path::Path;

use flapper_sim::Vec3;

use super::Reference;

/// Faster than any flapping robot could follow: the paper's robot cruises at 3.8-5.3 m/s.
pub const MAX_REFERENCE_SPEED_MPS: f64 = 15.0;
/// Largest time or coordinate accepted (s, m): far beyond any flight, small enough for exact sums.
pub const MAX_REFERENCE_VALUE: f64 = 1e6;
/// Longest reference accepted (s): one hour at 50 Hz is 180 000 points.
pub const MAX_REFERENCE_DURATION_S: f64 = 3600.0;

#[derive(Debug, thiserror::Error)]
pub enum ReferenceFileError {
    #[error("cannot read reference '{path}': {source}")]
    Read { path: String, source: std::io::Error },
    #[error("reference '{path}' line {line}: {message}")]
    Line { path: String, line: usize, message: String },
    #[error("reference '{path}': {message}")]
    Whole { path: String, message: String },
}

/// One row of a reference CSV as flapper writes it (`flapper reference`); the reader takes the same
/// column names in any order.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ReferenceRow {
    pub time_s: f64,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
}

/// The reference's points, sampled every `dt_s`, as CSV text (header `time_s,x_m,y_m,z_m`; times to
/// the millisecond, positions to 0.1 mm): the format [`parse_reference_csv`] reads back.
pub fn reference_csv_text(points: &[Vec3], dt_s: f64) -> String {
    // Rounded through decimal text, so that the shortest representation is the rounded one.
    let round = |v: f64, decimals: usize| format!("{v:.decimals$}").parse::<f64>().expect("a formatted number parses");
    let mut writer = csv::Writer::from_writer(Vec::new());
    for (k, p) in points.iter().enumerate() {
        let row = ReferenceRow {
            time_s: round(k as f64 * dt_s, 3),
            x_m: round(p.x, 4),
            y_m: round(p.y, 4),
            z_m: round(p.z, 4),
        };
        writer.serialize(row).expect("numbers serialize");
    }
    String::from_utf8(writer.into_inner().expect("writing to memory")).expect("CSV of numbers is UTF-8")
}

/// The columns a reference CSV must name, in the order the reader uses them.
pub const COLUMNS: [&str; 4] = ["time_s", "x_m", "y_m", "z_m"];

/// Where each of [`COLUMNS`] is in `header`, or why the header is refused.
fn column_order(header: &csv::StringRecord) -> Result<[usize; 4], String> {
    let expected = COLUMNS.join(",");
    if let Some(unknown) = header.iter().find(|name| !COLUMNS.contains(name)) {
        return Err(format!("unknown column '{unknown}' in the header (the columns are {expected}, in any order)"));
    }
    let mut order = [0; 4];
    for (slot, name) in order.iter_mut().zip(COLUMNS) {
        let found: Vec<usize> = header.iter().enumerate().filter(|(_, h)| *h == name).map(|(k, _)| k).collect();
        *slot = match found.as_slice() {
            [one] => *one,
            [] => return Err(format!("the header has no column '{name}' (the columns are {expected}, in any order)")),
            _ => return Err(format!("the header names '{name}' twice")),
        };
    }
    Ok(order)
}

/// Loads and checks a reference CSV, resampled every `dt_s`. It must cover at least
/// `lookahead_steps + 1` control steps.
pub fn load_reference_csv(path: &Path, dt_s: f64, lookahead_steps: usize) -> Result<Reference, ReferenceFileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| ReferenceFileError::Read { path: path.display().to_string(), source })?;
    parse_reference_csv(&text, &path.display().to_string(), dt_s, lookahead_steps)
}

/// As [`load_reference_csv`] from text; `origin` names it in errors.
pub fn parse_reference_csv(
    text: &str,
    origin: &str,
    dt_s: f64,
    lookahead_steps: usize,
) -> Result<Reference, ReferenceFileError> {
    let at_line = |line: usize, message: String| ReferenceFileError::Line { path: origin.to_owned(), line, message };
    let mut reader =
        csv::ReaderBuilder::new().has_headers(true).flexible(true).trim(csv::Trim::All).from_reader(text.as_bytes());
    // The first line is the header: one that is all numbers is a data row whose header is missing.
    if let Ok(header) = reader.headers()
        && header.len() >= 4
        && header.iter().take(4).all(|field| field.parse::<f64>().is_ok())
    {
        return Err(at_line(1, "is data, not a header: the first line names the columns (time_s,x_m,y_m,z_m)".into()));
    }
    let columns = column_order(reader.headers().map_err(|e| at_line(1, e.to_string()))?).map_err(|m| at_line(1, m))?;
    let mut samples: Vec<(f64, Vec3)> = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line() as usize);
            at_line(line, e.to_string())
        })?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        if record.len() != COLUMNS.len() {
            return Err(at_line(line, format!("expected 4 columns ({}), found {}", COLUMNS.join(","), record.len())));
        }
        let mut values = [0.0f64; 4];
        for (value, &column) in values.iter_mut().zip(&columns) {
            let field = &record[column];
            *value = field.parse().map_err(|_| at_line(line, format!("'{field}' is not a number")))?;
            if !value.is_finite() {
                return Err(at_line(line, format!("'{field}' is not finite")));
            }
            if value.abs() > MAX_REFERENCE_VALUE {
                return Err(at_line(line, format!("'{field}' is beyond +-{MAX_REFERENCE_VALUE} (s or m)")));
            }
        }
        let (time, position) = (values[0], Vec3::new(values[1], values[2], values[3]));
        if let Some(&(previous_time, previous)) = samples.last() {
            if time <= previous_time {
                return Err(at_line(line, format!("time {time} s does not increase (previous {previous_time} s)")));
            }
            let speed = (position - previous).length() / (time - previous_time);
            if speed > MAX_REFERENCE_SPEED_MPS {
                return Err(at_line(
                    line,
                    format!(
                        "speed {speed:.1} m/s since the previous point; no flying robot here follows more than {MAX_REFERENCE_SPEED_MPS} m/s"
                    ),
                ));
            }
        }
        samples.push((time, position));
    }
    let whole = |message: String| ReferenceFileError::Whole { path: origin.to_owned(), message };
    let (Some(&(t0, _)), Some(&(t1, _))) = (samples.first(), samples.last()) else {
        return Err(whole("no data rows".into()));
    };
    if t1 - t0 > MAX_REFERENCE_DURATION_S {
        return Err(whole(format!("covers {:.0} s; at most {MAX_REFERENCE_DURATION_S} s are accepted", t1 - t0)));
    }
    let needed_s = lookahead_steps as f64 * dt_s;
    if t1 - t0 < needed_s {
        return Err(whole(format!(
            "covers {:.3} s; at least {needed_s:.2} s are needed for the {lookahead_steps}-step lookahead",
            t1 - t0
        )));
    }
    // Resample by linear interpolation at t0, t0 + dt, ...
    let steps = ((t1 - t0) / dt_s + 1e-9).floor() as usize;
    let mut points = Vec::with_capacity(steps + 1);
    let mut segment = 0;
    for k in 0..=steps {
        let t = t0 + k as f64 * dt_s;
        while segment + 2 < samples.len() && samples[segment + 1].0 < t {
            segment += 1;
        }
        let ((ta, pa), (tb, pb)) = (samples[segment], samples[(segment + 1).min(samples.len() - 1)]);
        let u = if tb > ta { ((t - ta) / (tb - ta)).clamp(0.0, 1.0) } else { 0.0 };
        points.push(pa.lerp(pb, u));
    }
    Ok(Reference::new(origin, dt_s, points))
}

/// A reference given as positions already sampled every `dt_s` (rows of x, y, z in metres, e.g. a
/// numpy array from Python), checked as a CSV's rows are; `origin` names it in errors.
pub fn reference_from_points(
    points: &[[f64; 3]],
    origin: &str,
    dt_s: f64,
    lookahead_steps: usize,
) -> Result<Reference, ReferenceFileError> {
    let whole = |message: String| ReferenceFileError::Whole { path: origin.to_owned(), message };
    let mut checked: Vec<Vec3> = Vec::with_capacity(points.len());
    for (row, &[x, y, z]) in points.iter().enumerate() {
        if let Some(value) = [x, y, z].into_iter().find(|v| !v.is_finite() || v.abs() > MAX_REFERENCE_VALUE) {
            return Err(whole(format!(
                "row {row}: {value} is not a finite coordinate within +-{MAX_REFERENCE_VALUE} m"
            )));
        }
        let position = Vec3::new(x, y, z);
        if let Some(&previous) = checked.last() {
            let speed = (position - previous).length() / dt_s;
            if speed > MAX_REFERENCE_SPEED_MPS {
                return Err(whole(format!(
                    "row {row}: speed {speed:.1} m/s since the previous row (rows are {dt_s} s apart); at most {MAX_REFERENCE_SPEED_MPS} m/s"
                )));
            }
        }
        checked.push(position);
    }
    if checked.len() < lookahead_steps + 1 {
        return Err(whole(format!(
            "has {} rows; at least {} are needed for the {lookahead_steps}-step lookahead",
            checked.len(),
            lookahead_steps + 1
        )));
    }
    if (checked.len() - 1) as f64 * dt_s > MAX_REFERENCE_DURATION_S {
        return Err(whole(format!(
            "covers {:.0} s; at most {MAX_REFERENCE_DURATION_S} s are accepted",
            (checked.len() - 1) as f64 * dt_s
        )));
    }
    Ok(Reference::new(origin, dt_s, checked))
}

#[cfg(test)]
mod written_tests {
    use super::*;

    #[test]
    fn a_written_reference_reads_back() {
        let reference = super::super::named::named("loop", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.0).unwrap();
        let text = reference_csv_text(reference.points(), 0.02);
        assert!(text.starts_with("time_s,x_m,y_m,z_m\n"), "{}", &text[..40]);
        let back = parse_reference_csv(&text, "written", 0.02, 0).unwrap();
        assert_eq!(back.len(), reference.len());
        for (a, b) in back.points().iter().zip(reference.points()) {
            assert!((*a - *b).length() < 1e-3, "{a:?} vs {b:?}");
        }
    }
}
