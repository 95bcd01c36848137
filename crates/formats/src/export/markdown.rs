//! Markdown rendering of a [`Table`]: `| a | b |`, a `|---|---|` rule, one
//! line per row; a `|` inside a cell is escaped as `\|`.

use super::Table;

fn esc(s: &str) -> String {
    s.replace('|', "\\|")
}

/// Render `t` as Markdown.
pub fn render(t: &Table) -> String {
    let cols: Vec<usize> = t.displayed().collect();
    let head: Vec<String> = cols.iter().map(|&i| esc(&t.columns[i].header)).collect();
    let mut s = format!("| {} |\n|{}\n", head.join(" | "), "---|".repeat(cols.len()));
    for r in &t.rows {
        let cells: Vec<String> = cols.iter().map(|&i| esc(r[i].shown())).collect();
        s.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    s
}
