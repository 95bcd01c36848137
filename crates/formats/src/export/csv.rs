//! CSV rendering of a [`Table`] (RFC 4180): a header line of the columns' CSV
//! names, fields quoted when they hold a comma, quote or line break (quotes doubled),
//! numbers at full precision (shortest round-trip), missing values empty, intervals as two
//! fields `<name>_lo`, `<name>_hi`.

use super::{Cell, Table};

/// Quote a field where RFC 4180 requires it.
pub fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn number(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else if v.is_nan() {
        "NaN".into()
    } else if v > 0.0 {
        "inf".into()
    } else {
        "-inf".into()
    }
}

/// Render `t` as CSV.
pub fn render(t: &Table) -> String {
    let cols: Vec<usize> = (0..t.columns.len())
        .filter(|&i| t.columns[i].in_csv())
        .collect();
    let is_interval = |i: usize| t.rows.iter().any(|r| matches!(r[i], Cell::Interval { .. }));
    let mut head = Vec::new();
    for &i in &cols {
        let c = &t.columns[i].csv;
        if is_interval(i) {
            head.push(field(&format!("{c}_lo")));
            head.push(field(&format!("{c}_hi")));
        } else {
            head.push(field(c));
        }
    }
    let mut s = head.join(",");
    s.push('\n');
    for r in &t.rows {
        let mut f = Vec::new();
        for &i in &cols {
            let two = is_interval(i);
            match &r[i] {
                Cell::Interval { lo, hi, .. } => {
                    f.push(number(*lo));
                    f.push(number(*hi));
                }
                Cell::Num { value, .. } => f.push(number(*value)),
                Cell::Missing(_) => f.push(String::new()),
                Cell::Text(x) | Cell::Link { text: x, .. } => f.push(field(x)),
            }
            if two && !matches!(r[i], Cell::Interval { .. }) {
                f.push(String::new());
            }
        }
        s.push_str(&f.join(","));
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::super::{Cell, Column, Table};

    #[test]
    fn quotes_and_intervals() {
        let mut t = Table::new(vec![
            Column::new("name", "name"),
            Column::new("95% interval", "ci"),
            Column::new("note", "note").display_only(),
        ]);
        t.push(vec![
            Cell::text("a \"b\", c"),
            Cell::interval(0.1, 0.25, "[0.10, 0.25]"),
            Cell::text("x"),
        ]);
        t.push(vec![Cell::text("d"), Cell::missing("—"), Cell::text("y")]);
        assert_eq!(
            t.to_csv(),
            "name,ci_lo,ci_hi\n\"a \"\"b\"\", c\",0.1,0.25\nd,,\n"
        );
        assert_eq!(
            t.to_markdown(),
            "| name | 95% interval | note |\n|---|---|---|\n| a \"b\", c | [0.10, 0.25] | x |\n| d | — | y |\n"
        );
    }
}
