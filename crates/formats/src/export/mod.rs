//! One table model (and [`LineChart`], curves as data), rendered to Markdown ([`markdown`]), CSV ([`csv`]) and HTML
//! (`report::html_table`, all HTML lives in the report module), after sharkdp/hyperfine's
//! `src/export/`.
//!
//! A [`Table`] is columns and rows of typed [`Cell`]s. A number is kept as a number
//! ([`Cell::Num`]: the value and the text shown for it); an interval as its two ends
//! ([`Cell::Interval`]). Markdown and HTML print the shown text; CSV prints the values at
//! full precision (Rust's shortest round-trip form) so a script reads the table back as
//! numbers: an interval column becomes two CSV columns, `<name>_lo` and `<name>_hi`, and a
//! column can be kept out of the CSV or out of the displayed tables.
//!
//! ```
//! use pradar_formats::export::{Cell, Column, Table};
//! let mut t = Table::new(vec![Column::new("quantity", "quantity"), Column::new("value (m)", "value_m")]);
//! t.push(vec![Cell::text("d_c"), Cell::num(2.0345, format!("{:.2}", 2.0345))]);
//! assert_eq!(t.to_markdown(), "| quantity | value (m) |\n|---|---|\n| d_c | 2.03 |\n");
//! assert_eq!(t.to_csv(), "quantity,value_m\nd_c,2.0345\n");
//! ```

pub mod csv;
pub mod markdown;

/// Curves as data (the report draws them: `report::line_plots`): named series of (x, y)
/// points under a title and axis labels.
#[derive(Debug, Clone)]
pub struct LineChart {
    /// Caption.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// (name, points) per series.
    pub series: Vec<(String, Vec<(f64, f64)>)>,
}

/// One cell of a [`Table`].
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// Text, shown and written as is.
    Text(String),
    /// A number: its value (written to CSV) and the text shown for it.
    Num {
        /// The value.
        value: f64,
        /// The text Markdown and HTML show.
        shown: String,
    },
    /// An interval [lo, hi]: two CSV fields, one shown text.
    Interval {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
        /// The text Markdown and HTML show.
        shown: String,
    },
    /// No value: an empty CSV field, `shown` in Markdown and HTML (e.g. "—").
    Missing(String),
    /// A hyperlink: `text` (CSV: the text), linked to `href` in HTML.
    Link {
        /// Link text.
        text: String,
        /// Target.
        href: String,
    },
}

impl Cell {
    /// A text cell.
    pub fn text(s: impl Into<String>) -> Cell {
        Cell::Text(s.into())
    }

    /// A number with the text shown for it.
    pub fn num(value: f64, shown: impl Into<String>) -> Cell {
        Cell::Num {
            value,
            shown: shown.into(),
        }
    }

    /// A number shown with `decimals` decimals.
    pub fn fixed(value: f64, decimals: usize) -> Cell {
        Cell::num(value, format!("{value:.decimals$}"))
    }

    /// An integer count.
    pub fn count(n: usize) -> Cell {
        Cell::num(n as f64, n.to_string())
    }

    /// An interval with the text shown for it.
    pub fn interval(lo: f64, hi: f64, shown: impl Into<String>) -> Cell {
        Cell::Interval {
            lo,
            hi,
            shown: shown.into(),
        }
    }

    /// A missing value shown as `shown`.
    pub fn missing(shown: impl Into<String>) -> Cell {
        Cell::Missing(shown.into())
    }

    /// The text Markdown and HTML show.
    pub fn shown(&self) -> &str {
        match self {
            Cell::Text(s) | Cell::Missing(s) => s,
            Cell::Num { shown, .. } | Cell::Interval { shown, .. } => shown,
            Cell::Link { text, .. } => text,
        }
    }
}

/// Where a column appears.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shown {
    /// In every rendering.
    Everywhere,
    /// Only in the CSV (e.g. a unit column beside a value shown with its unit).
    CsvOnly,
    /// Only in Markdown and HTML (e.g. a combined text column the CSV splits elsewhere).
    DisplayOnly,
}

/// A column: its displayed header, an optional shorter header for HTML, and its CSV name.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Header in Markdown (and HTML unless `html_header` is set).
    pub header: String,
    /// Header in HTML, where it differs.
    pub html_header: Option<String>,
    /// CSV column name (an interval column writes `<csv>_lo` and `<csv>_hi`).
    pub csv: String,
    /// Where the column appears.
    pub shown: Shown,
}

impl Column {
    /// A column shown everywhere.
    pub fn new(header: impl Into<String>, csv: impl Into<String>) -> Column {
        Column {
            header: header.into(),
            html_header: None,
            csv: csv.into(),
            shown: Shown::Everywhere,
        }
    }

    /// Use a different header in HTML.
    pub fn html(mut self, h: impl Into<String>) -> Column {
        self.html_header = Some(h.into());
        self
    }

    /// Keep the column out of Markdown and HTML.
    pub fn csv_only(mut self) -> Column {
        self.shown = Shown::CsvOnly;
        self
    }

    /// Keep the column out of the CSV.
    pub fn display_only(mut self) -> Column {
        self.shown = Shown::DisplayOnly;
        self
    }

    /// Whether Markdown and HTML show it.
    pub fn displayed(&self) -> bool {
        self.shown != Shown::CsvOnly
    }

    /// Whether the CSV has it.
    pub fn in_csv(&self) -> bool {
        self.shown != Shown::DisplayOnly
    }
}

/// Columns and rows of cells.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// The columns.
    pub columns: Vec<Column>,
    /// The rows, each with one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(columns: Vec<Column>) -> Table {
        Table {
            columns,
            rows: Vec::new(),
        }
    }

    /// Append a row (one cell per column; a short row is padded with empty text).
    pub fn push(&mut self, mut row: Vec<Cell>) {
        debug_assert!(
            row.len() <= self.columns.len(),
            "row longer than the header"
        );
        row.resize(self.columns.len(), Cell::text(""));
        self.rows.push(row);
    }

    /// Rendered as a GitHub-flavoured Markdown table.
    pub fn to_markdown(&self) -> String {
        markdown::render(self)
    }

    /// Rendered as RFC 4180 CSV with a header line.
    pub fn to_csv(&self) -> String {
        csv::render(self)
    }

    /// The displayed (header, cells) of each displayed column, in order.
    pub fn displayed(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.columns.len()).filter(|&i| self.columns[i].displayed())
    }
}
