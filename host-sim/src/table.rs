//! What the calculators print: named values with their units, and tables,
//! as a person reads them on the terminal or as CSV and JSON for scripts.

use std::fmt::Write;

/// How results are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Format {
    /// Aligned, every number with its unit.
    #[default]
    Text,
    /// Comma-separated, a header naming each column and its unit.
    Csv,
    /// One JSON object: `values` by key, `rows` of the table.
    Json,
}

/// A column or a value: its key (for CSV and JSON), what it is, its unit.
#[derive(Clone, Debug)]
pub struct Field {
    /// `snake_case`, the unit in it where it has one (`phi_deg`).
    pub key: &'static str,
    /// What a person reads (`cone half-angle φ`).
    pub label: String,
    /// `mm`, `°`, `rpm`, … (empty: a count or a word).
    pub unit: &'static str,
}

/// One printed figure.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A number and its decimals.
    Num(f64, usize),
    /// A whole number.
    Int(i64),
    /// Text.
    Text(String),
}

impl Cell {
    fn plain(&self) -> String {
        match self {
            Cell::Num(v, d) => {
                let t = format!("{v:.d$}");
                // No "-0.000": a value that rounds to zero has no sign.
                match t.strip_prefix('-') {
                    Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
                    _ => t,
                }
            }
            Cell::Int(n) => n.to_string(),
            Cell::Text(t) => t.clone(),
        }
    }

    fn json(&self) -> String {
        match self {
            Cell::Num(v, d) if v.is_finite() => format!("{v:.d$}"),
            Cell::Num(..) => "null".into(),
            Cell::Int(n) => n.to_string(),
            Cell::Text(t) => json_string(t),
        }
    }
}

fn json_string(t: &str) -> String {
    let mut s = String::from("\"");
    for c in t.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            c if (c as u32) < 0x20 => {
                let _ = write!(s, "\\u{:04x}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

fn csv_field(t: &str) -> String {
    if t.contains([',', '"', '\n']) {
        format!("\"{}\"", t.replace('"', "\"\""))
    } else {
        t.to_string()
    }
}

/// A calculator's answer: a title, named values, and optionally a table.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// What was computed.
    pub title: String,
    /// Named results, in order.
    pub values: Vec<(Field, Cell)>,
    /// The table's columns, and its rows (each as long as the columns).
    pub columns: Vec<Field>,
    /// Rows.
    pub rows: Vec<Vec<Cell>>,
    /// Notes printed under the text form (decisions, warnings).
    pub notes: Vec<String>,
}

/// A field.
pub fn field(key: &'static str, label: &str, unit: &'static str) -> Field {
    Field {
        key,
        label: label.to_string(),
        unit,
    }
}

impl Report {
    /// An empty report titled `title`.
    pub fn new(title: &str) -> Report {
        Report {
            title: title.to_string(),
            ..Report::default()
        }
    }

    /// Adds a named value.
    pub fn value(&mut self, key: &'static str, label: &str, unit: &'static str, cell: Cell) {
        self.values.push((field(key, label, unit), cell));
    }

    /// The report in `format`, ending with a newline.
    pub fn render(&self, format: Format) -> String {
        match format {
            Format::Text => self.text(),
            Format::Csv => self.csv(),
            Format::Json => self.json(),
        }
    }

    fn text(&self) -> String {
        let mut s = String::new();
        if !self.title.is_empty() {
            let _ = writeln!(s, "{}", self.title);
        }
        let width = self
            .values
            .iter()
            .map(|(f, _)| f.label.chars().count())
            .max()
            .unwrap_or(0);
        for (f, c) in &self.values {
            let pad = width - f.label.chars().count();
            let unit = match f.unit {
                "" => String::new(),
                "°" => "°".into(),
                u => format!(" {u}"),
            };
            let _ = writeln!(s, "  {}{} {}{unit}", f.label, " ".repeat(pad), c.plain());
        }
        if !self.columns.is_empty() {
            if !self.values.is_empty() {
                s.push('\n');
            }
            let heads: Vec<String> = self
                .columns
                .iter()
                .map(|c| match c.unit {
                    "" => c.label.clone(),
                    u => format!("{}, {u}", c.label),
                })
                .collect();
            let cells: Vec<Vec<String>> = self
                .rows
                .iter()
                .map(|r| r.iter().map(Cell::plain).collect())
                .collect();
            let widths: Vec<usize> = heads
                .iter()
                .enumerate()
                .map(|(i, h)| {
                    cells
                        .iter()
                        .filter_map(|r| r.get(i))
                        .map(|c| c.chars().count())
                        .chain([h.chars().count()])
                        .max()
                        .unwrap_or(0)
                })
                .collect();
            let line = |s: &mut String, items: &[String]| {
                let mut out = String::from(" ");
                for (i, w) in widths.iter().enumerate() {
                    let item = items.get(i).map_or("", String::as_str);
                    let pad = w - item.chars().count();
                    let _ = write!(out, "  {}{item}", " ".repeat(pad));
                }
                let _ = writeln!(s, "{}", out.trim_end());
            };
            line(&mut s, &heads);
            for r in &cells {
                line(&mut s, r);
            }
        }
        for n in &self.notes {
            let _ = writeln!(s, "{n}");
        }
        s
    }

    fn csv(&self) -> String {
        let mut s = String::new();
        let head = |f: &Field| match f.unit {
            "" => f.key.to_string(),
            u => format!("{} [{u}]", f.key),
        };
        if self.columns.is_empty() {
            let _ = writeln!(s, "key,value,unit");
            for (f, c) in &self.values {
                let _ = writeln!(s, "{},{},{}", f.key, csv_field(&c.plain()), f.unit);
            }
        } else {
            let heads: Vec<String> = self.columns.iter().map(|f| csv_field(&head(f))).collect();
            let _ = writeln!(s, "{}", heads.join(","));
            for r in &self.rows {
                let cells: Vec<String> = r.iter().map(|c| csv_field(&c.plain())).collect();
                let _ = writeln!(s, "{}", cells.join(","));
            }
        }
        s
    }

    fn json(&self) -> String {
        let values: Vec<String> = self
            .values
            .iter()
            .map(|(f, c)| format!("{}:{}", json_string(f.key), c.json()))
            .collect();
        let mut s = format!("{{\"values\":{{{}}}", values.join(","));
        if !self.columns.is_empty() {
            let units: Vec<String> = self
                .columns
                .iter()
                .map(|f| format!("{}:{}", json_string(f.key), json_string(f.unit)))
                .collect();
            let _ = write!(s, ",\"units\":{{{}}}", units.join(","));
            let rows: Vec<String> = self
                .rows
                .iter()
                .map(|r| {
                    let cells: Vec<String> = self
                        .columns
                        .iter()
                        .zip(r)
                        .map(|(f, c)| format!("{}:{}", json_string(f.key), c.json()))
                        .collect();
                    format!("{{{}}}", cells.join(","))
                })
                .collect();
            let _ = write!(s, ",\"rows\":[{}]", rows.join(","));
        }
        s.push_str("}\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Report {
        let mut r = Report::new("sample");
        r.value(
            "phi_deg",
            "cone half-angle φ",
            "°",
            Cell::Num(35.264389682, 5),
        );
        r.value("n_max_rpm", "n max", "rpm", Cell::Int(240));
        r.columns = vec![field("x_mm", "x", "mm"), field("what", "what", "")];
        r.rows = vec![
            vec![Cell::Num(10.0, 1), Cell::Text("a, \"b\"".into())],
            vec![Cell::Num(200.0, 1), Cell::Text("c".into())],
        ];
        r
    }

    #[test]
    fn text_aligns_and_names_units() {
        let t = sample().render(Format::Text);
        assert!(t.contains("  cone half-angle φ 35.26439°\n"), "{t}");
        assert!(t.contains("  n max             240 rpm\n"), "{t}");
        assert!(t.contains("   x, mm    what\n"), "{t}");
        assert!(t.contains("   200.0       c\n"), "{t}");
        assert!(t.contains("    10.0  a, \"b\"\n"), "{t}");
    }

    #[test]
    fn csv_and_json_are_machine_readable() {
        let r = sample();
        assert_eq!(
            r.render(Format::Csv),
            "x_mm [mm],what\n10.0,\"a, \"\"b\"\"\"\n200.0,c\n"
        );
        assert_eq!(
            r.render(Format::Json),
            "{\"values\":{\"phi_deg\":35.26439,\"n_max_rpm\":240},\"units\":{\"x_mm\":\"mm\",\"what\":\"\"},\
             \"rows\":[{\"x_mm\":10.0,\"what\":\"a, \\\"b\\\"\"},{\"x_mm\":200.0,\"what\":\"c\"}]}\n"
        );
        let mut v = Report::new("v");
        v.value("a_mm", "a", "mm", Cell::Num(f64::NAN, 2));
        assert_eq!(v.render(Format::Csv), "key,value,unit\na_mm,NaN,mm\n");
        assert_eq!(v.render(Format::Json), "{\"values\":{\"a_mm\":null}}\n");
    }
}

/// `--csv` / `--json` of a calculator's command line.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct OutArgs {
    /// Print CSV (a header with each column's unit) instead of a table.
    #[arg(long, conflicts_with = "json")]
    pub csv: bool,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl OutArgs {
    /// The format asked for.
    pub fn format(&self) -> Format {
        match (self.csv, self.json) {
            (true, _) => Format::Csv,
            (_, true) => Format::Json,
            _ => Format::Text,
        }
    }
}
