//! The "paper vs flapper" table. Each of our numbers is read back from a file the report run wrote
//! (a JSON pointer into it) and formatted here; a row names its sources, so anyone (and a test) can
//! check the page against the files.

use std::path::Path;

use serde_json::Value;

use crate::ReportError;

/// How a source's value is printed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    /// Fixed point with this many decimals.
    Fixed(usize),
    /// Scientific with this many decimals.
    Scientific(usize),
    /// `yes` / `no`.
    YesNo,
    /// A string as it is.
    Text,
}

/// One number of a row: `file` (relative to the report folder), a JSON pointer into it, a scale
/// applied before formatting, and the format.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    pub file: String,
    pub pointer: String,
    pub scale: f64,
    pub format: Format,
}

impl Source {
    fn new(file: &str, pointer: &str, scale: f64, format: Format) -> Self {
        Self { file: file.to_owned(), pointer: pointer.to_owned(), scale, format }
    }

    /// The value in the report folder `out`, formatted; `None` if the file or the key is missing.
    pub fn read(&self, out: &Path) -> Option<String> {
        let text = std::fs::read_to_string(out.join(&self.file)).ok()?;
        let json: Value = serde_json::from_str(&text).ok()?;
        let value = json.pointer(&self.pointer)?;
        Some(match self.format {
            Format::Fixed(d) => format!("{:.*}", d, value.as_f64()? * self.scale),
            Format::Scientific(d) => format!("{:.*e}", d, value.as_f64()? * self.scale),
            Format::YesNo => {
                if value.as_bool()? {
                    "yes".into()
                } else {
                    "no".into()
                }
            }
            Format::Text => value.as_str()?.to_owned(),
        })
    }

    /// `file#pointer*scale:format`, as written in the CSV.
    pub fn describe(&self) -> String {
        let format = match self.format {
            Format::Fixed(d) => format!("f{d}"),
            Format::Scientific(d) => format!("e{d}"),
            Format::YesNo => "yesno".into(),
            Format::Text => "text".into(),
        };
        format!("{}#{}*{}:{format}", self.file, self.pointer, self.scale)
    }

    /// Reads back [`Source::describe`].
    pub fn parse(text: &str) -> Option<Self> {
        let (file, rest) = text.split_once('#')?;
        let (pointer, rest) = rest.rsplit_once('*')?;
        let (scale, format) = rest.split_once(':')?;
        let format = match format {
            "yesno" => Format::YesNo,
            "text" => Format::Text,
            f if f.starts_with('f') => Format::Fixed(f[1..].parse().ok()?),
            f if f.starts_with('e') => Format::Scientific(f[1..].parse().ok()?),
            _ => return None,
        };
        Some(Self { file: file.to_owned(), pointer: pointer.to_owned(), scale: scale.parse().ok()?, format })
    }
}

/// One claim of the paper beside ours: a row of `paper_vs_flapper.csv`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Row {
    pub claim: String,
    pub paper: String,
    /// Our figures, each the formatted value of a source.
    pub flapper: String,
    pub verdict: String,
    /// In the file: space-separated descriptions ([`Source::describe`]).
    #[serde(serialize_with = "described")]
    pub sources: Vec<Source>,
}

fn described<S: serde::Serializer>(sources: &[Source], serializer: S) -> Result<S::Ok, S::Error> {
    serializer.collect_str(&sources.iter().map(Source::describe).collect::<Vec<_>>().join(" "))
}

/// The table being built from the files of the report folder `out`.
struct Table<'a> {
    out: &'a Path,
    rows: Vec<Row>,
}

impl Table<'_> {
    /// Adds a row whose text `text` makes from its sources' values when every source is there;
    /// otherwise the row says "not measured".
    fn row(&mut self, claim: &str, paper: &str, sources: Vec<Source>, text: &dyn Fn(&[String]) -> (String, String)) {
        let values: Option<Vec<String>> = sources.iter().map(|s| s.read(self.out)).collect();
        let (flapper, verdict) = match values {
            Some(v) => text(&v),
            None => ("not measured".into(), "-".into()),
        };
        self.rows.push(Row { claim: claim.into(), paper: paper.into(), flapper, verdict, sources });
    }
}

/// What the paper says, and the files of a report run.
pub fn compare(out: &Path) -> Result<Vec<Row>, ReportError> {
    let mut table = Table { out, rows: Vec::new() };
    for add in [gait, flight_modes, identification, manoeuvres, training_cost, robustness, phase_portraits] {
        add(&mut table);
    }
    Ok(table.rows)
}

/// The learned gait: flapping frequency and the energy in its fundamental.
fn gait(table: &mut Table) {
    let cruise = "tracking/cruise/summary.json";
    table.row(
        "learned flapping frequency (cruise at 3.8 m/s)",
        "5.3 Hz",
        (0..3).map(|k| Source::new(cruise, &format!("/summary/frequency_hz/{k}"), 1.0, Format::Fixed(2))).collect(),
        &|v| {
            let flap: f64 = v[0].parse().unwrap_or(f64::NAN);
            let off = 100.0 * (flap / 5.3 - 1.0);
            (
                format!("{} / {} / {} Hz (flap / wing pitch / tail)", v[0], v[1], v[2]),
                if off.abs() <= 10.0 {
                    format!("agrees within 10% (flap {off:+.0}%)")
                } else {
                    format!("differs: flap {off:+.0}%")
                },
            )
        },
    );
    table.row(
        "energy in the fundamental frequency",
        "36.8-38.7% (flap, wing pitch, tail)",
        (0..3)
            .map(|k| Source::new(cruise, &format!("/summary/energy_fraction/{k}"), 100.0, Format::Fixed(1)))
            .collect(),
        &|v| {
            let within = v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| (30.0..=45.0).contains(&p)));
            (
                format!("{}% / {}% / {}%", v[0], v[1], v[2]),
                if within { "agrees (30-45%)".into() } else { "differs".into() },
            )
        },
    );
}

/// Flight modes: gliding where the path allows it, and level flight at the speed of the paper's phase
/// portraits.
fn flight_modes(table: &mut Table) {
    let modes = "modes/modes.json";
    table.row(
        "switches between flight modes: glides when possible (glide segment of longitudinal)",
        "glides instead of flapping when possible",
        vec![
            Source::new(modes, "/segments/2/glide_fraction", 1.0, Format::Fixed(2)),
            Source::new(modes, "/segments/3/glide_fraction", 1.0, Format::Fixed(2)),
            Source::new(modes, "/segments/2/flap_amplitude_deg", 1.0, Format::Fixed(0)),
            Source::new(modes, "/segments/0/flap_amplitude_deg", 1.0, Format::Fixed(0)),
        ],
        &|v| {
            let glides = v[0].parse::<f64>().is_ok_and(|f| f >= 0.5);
            (
                format!(
                    "wings held {} of the glide segment, {} of the dive; flap amplitude {} deg gliding vs {} deg in cruise",
                    v[0], v[1], v[2], v[3]
                ),
                if glides { "agrees (glide fraction >= 0.5)".into() } else { "differs: flaps through the glide".into() },
            )
        },
    );
    table.row(
        "level flight at 3 m/s (the phase portraits' speed)",
        "flown",
        vec![Source::new(
            "robustness/longitudinal/robustness.json",
            "/envelope/slowest_sustained_mps",
            1.0,
            Format::Fixed(1),
        )],
        &|v| {
            let slow_enough = v[0].parse::<f64>().is_ok_and(|s| s <= 3.0);
            (
                format!("slowest level flight completed in >= 90% of episodes: {} m/s", v[0]),
                if slow_enough { "agrees".into() } else { format!("differs: not below {} m/s", v[0]) },
            )
        },
    );
}

/// The identified closed loop: its error, poles and zeros.
fn identification(table: &mut Table) {
    let sysid = "sysid/sysid.json";
    table.row(
        "identification MSE of the closed loop",
        "5.6e-5 m^2",
        ["x", "y", "z"]
            .iter()
            .map(|a| Source::new(sysid, &format!("/{a}/mse_validation"), 1.0, Format::Scientific(1)))
            .collect(),
        &|v| {
            let worst = v.iter().filter_map(|x| x.parse::<f64>().ok()).fold(0.0, f64::max);
            (
                format!("x {} / y {} / z {} m^2", v[0], v[1], v[2]),
                if worst <= 1e-4 {
                    "agrees".into()
                } else {
                    format!("higher: up to {:.0}x the paper's", worst / 5.6e-5)
                },
            )
        },
    );
    table.row(
        "identified model's fit to validation flights (input: the target point ahead, lead estimated)",
        "not reported (input: the current desired position)",
        ["x", "y", "z"]
            .iter()
            .flat_map(|a| {
                [
                    Source::new(sysid, &format!("/{a}/fit_percent"), 1.0, Format::Fixed(1)),
                    Source::new(sysid, &format!("/{a}/input_lead_s"), 1.0, Format::Fixed(2)),
                ]
            })
            .collect(),
        &|v| {
            let worst = [&v[0], &v[2], &v[4]].iter().filter_map(|x| x.parse::<f64>().ok()).fold(100.0, f64::min);
            (
                format!("x {}% ({} s ahead) / y {}% ({} s) / z {}% ({} s)", v[0], v[1], v[2], v[3], v[4], v[5]),
                if worst >= 80.0 { "predicts the flight".into() } else { format!("weak: {worst:.0}% on one axis") },
            )
        },
    );
    for (claim, key) in [
        ("closed-loop poles in the left half plane (BIBO stable)", "bibo_stable"),
        ("zeros in the left half plane (minimum phase)", "minimum_phase"),
    ] {
        table.row(
            claim,
            "yes, every axis",
            ["x", "y", "z"].iter().map(|a| Source::new(sysid, &format!("/{a}/{key}"), 1.0, Format::YesNo)).collect(),
            &|v| {
                (
                    format!("x {}, y {}, z {}", v[0], v[1], v[2]),
                    if v.iter().all(|x| x == "yes") { "agrees".into() } else { "differs".into() },
                )
            },
        );
    }
}

/// The manoeuvres of Figs. 10-11, flown.
fn manoeuvres(table: &mut Table) {
    for (name, claim) in [
        ("sharp-turn", "180 deg turn in 1.2 s"),
        ("loop", "loop in 3 s"),
        ("roll-off-the-bottom", "roll-off-the-bottom in 1.8 s"),
        ("aerobatic", "aerobatic trajectory"),
    ] {
        let file = format!("tracking/{name}/summary.json");
        let mut sources = vec![
            Source::new(&file, "/summary/completed", 1.0, Format::Fixed(0)),
            Source::new(&file, "/summary/episodes", 1.0, Format::Fixed(0)),
        ];
        let manoeuvre = name != "aerobatic";
        if manoeuvre {
            sources.push(Source::new(&file, "/summary/manoeuvre/mean_max_error_m", 1.0, Format::Fixed(2)));
        } else {
            sources.push(Source::new(&file, "/summary/mean_rms_error_m", 1.0, Format::Fixed(2)));
        }
        table.row(claim, "flown, tracking the reference", sources, &|v| {
            let (done, of): (f64, f64) = (v[0].parse().unwrap_or(0.0), v[1].parse().unwrap_or(1.0));
            let detail = if manoeuvre {
                format!("largest error in it {} m (mean)", v[2])
            } else {
                format!("RMS error {} m", v[2])
            };
            (
                format!("completed {}/{}; {detail}", v[0], v[1]),
                if done >= 0.9 * of { "agrees".into() } else { format!("partly: {:.0}% completed", 100.0 * done / of) },
            )
        });
    }
}

/// What training cost.
fn training_cost(table: &mut Table) {
    let training = "training/training.json";
    table.row(
        "training cost",
        "30 M steps in about 5 h on 8 cores",
        vec![
            Source::new(training, "/total_env_steps", 1e-6, Format::Fixed(1)),
            Source::new(training, "/total_wall_time_s", 1.0 / 3600.0, Format::Fixed(2)),
        ],
        &|v| {
            let (steps, hours): (f64, f64) = (v[0].parse().unwrap_or(0.0), v[1].parse().unwrap_or(0.0));
            let ratio = if hours > 0.0 { (steps / hours) / (30.0 / 5.0) } else { f64::NAN };
            (
                format!("{} M steps in {} h (the whole curriculum, validation included)", v[0], v[1]),
                format!("{ratio:.1}x the paper's steps per hour"),
            )
        },
    );
}

/// Robustness to the fluid coefficients and to Table III at once.
fn robustness(table: &mut Table) {
    let robustness = |r: &str| format!("robustness/{r}/robustness.json");
    let widest_all = |r: &str| -> Option<String> {
        let json: Value = serde_json::from_str(&std::fs::read_to_string(table.out.join(robustness(r))).ok()?).ok()?;
        let fluid = json.get("fluid")?.as_array()?;
        let (k, _) = fluid
            .iter()
            .enumerate()
            .filter(|(_, f)| f["coefficient"] == "all")
            .max_by(|a, b| a.1["range"].as_f64().partial_cmp(&b.1["range"].as_f64()).expect("finite ranges"))?;
        Some(format!("/fluid/{k}/success_rate"))
    };
    let pointers: Vec<Source> = ["longitudinal", "lateral"]
        .iter()
        .filter_map(|r| widest_all(r).map(|p| Source::new(&robustness(r), &p, 100.0, Format::Fixed(0))))
        .collect();
    table.row(
        "success with all five fluid coefficients randomized x[0.5, 1.5]",
        "relatively successful (Fig. 9)",
        pointers,
        &|v| {
            let text = v
                .iter()
                .zip(["longitudinal", "lateral"])
                .map(|(x, r)| format!("{r} {x}%"))
                .collect::<Vec<_>>()
                .join(", ");
            let ok = v.len() == 2 && v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| p >= 80.0));
            (text, if ok { "agrees (>= 80%)".into() } else { "partly: below 80% somewhere".into() })
        },
    );
    table.row(
        "most sensitive fluid coefficient",
        "Kutta lift C_K",
        ["longitudinal", "lateral"]
            .iter()
            .map(|r| Source::new(&robustness(r), "/most_sensitive_coefficient", 1.0, Format::Text))
            .collect(),
        &|v| {
            (
                format!("longitudinal {}, lateral {}", v[0], v[1]),
                if v.iter().all(|x| x == "kutta") {
                    "agrees".into()
                } else if v.iter().any(|x| x == "kutta") {
                    "partly".into()
                } else {
                    "differs".into()
                },
            )
        },
    );
    table.row(
        "everything in Table III randomized at once",
        "tracks (Fig. 8)",
        ["longitudinal", "lateral"]
            .iter()
            .map(|r| Source::new(&robustness(r), "/table_iii/success_rate", 100.0, Format::Fixed(0)))
            .collect(),
        &|v| {
            let ok = v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| p >= 90.0));
            (
                format!("success longitudinal {}%, lateral {}%", v[0], v[1]),
                if ok { "agrees (>= 90%)".into() } else { "partly: below 90%".into() },
            )
        },
    );
}

/// The phase portraits' claims, one row each, as `flapper phase` checks them.
fn phase_portraits(table: &mut Table) {
    let claims = std::fs::read_to_string(table.out.join("phase/phase.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .and_then(|j| j["claims"].as_array().map(|a| a.len()))
        .unwrap_or(0);
    for k in 0..claims {
        let claim = Source::new("phase/phase.json", &format!("/claims/{k}/claim"), 1.0, Format::Text);
        let paper = claim.read(table.out).unwrap_or_default();
        table.row(
            &format!("phase portrait (Fig. 6-7): {paper}"),
            "as stated",
            vec![
                Source::new("phase/phase.json", &format!("/claims/{k}/ours"), 1.0, Format::Text),
                Source::new("phase/phase.json", &format!("/claims/{k}/confirmed"), 1.0, Format::YesNo),
            ],
            &|v| {
                (
                    format!("{} (confirmed: {})", v[0], v[1]),
                    if v[1] == "yes" { "agrees".into() } else { "differs".into() },
                )
            },
        );
    }
}

/// `paper_vs_flapper.csv`: claim, paper, flapper, verdict, sources (space-separated descriptions).
pub fn write_csv(rows: &[Row], path: &Path) -> Result<(), ReportError> {
    flapper_files::write_csv_records(path, rows)
        .map_err(|e| ReportError::Write { path: path.to_owned(), message: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_source_reads_formats_and_round_trips() {
        let dir = std::env::temp_dir().join(format!("flapper-comparison-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("a")).unwrap();
        std::fs::write(dir.join("a/b.json"), r#"{"x": [0.5, 2.0], "ok": true, "name": "kutta"}"#).unwrap();
        let s = Source::new("a/b.json", "/x/0", 100.0, Format::Fixed(1));
        assert_eq!(s.read(&dir).as_deref(), Some("50.0"));
        assert_eq!(Source::parse(&s.describe()), Some(s));
        assert_eq!(Source::new("a/b.json", "/x/1", 1.0, Format::Scientific(1)).read(&dir).as_deref(), Some("2.0e0"));
        assert_eq!(Source::new("a/b.json", "/ok", 1.0, Format::YesNo).read(&dir).as_deref(), Some("yes"));
        assert_eq!(Source::new("a/b.json", "/name", 1.0, Format::Text).read(&dir).as_deref(), Some("kutta"));
        assert_eq!(Source::new("a/b.json", "/missing", 1.0, Format::Text).read(&dir), None);
        assert_eq!(Source::new("a/none.json", "/x", 1.0, Format::Text).read(&dir), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
