//! One description of a report page (title, status, text, tables, figures), rendered
//! to Markdown (`index.md`) and to a self-contained HTML file (`index.html`: every
//! chart's SVG inline, a small inline style sheet, no scripts, nothing fetched from
//! the network), so that the two never drift. Writing a page also leaves the run's
//! metadata beside it and refreshes the run list of the folder above
//! ([`super::runs`]).

use super::format::table;
use super::plot::Chart;
use super::runs::{self, Run};
use crate::error::Result;
use crate::io::write::atomic_write;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A piece of running text.
#[derive(Debug, Clone, PartialEq)]
pub enum Span {
    /// Plain text.
    Text(String),
    /// A file name, a command or an identifier (`code`).
    Code(String),
    /// Emphasised text.
    Strong(String),
    /// A link relative to the page (a file beside it).
    Link {
        /// The text shown.
        text: String,
        /// The target, relative to the page.
        href: String,
    },
}

/// Plain text.
pub fn text(s: impl Into<String>) -> Span {
    Span::Text(s.into())
}

/// Code text (a file name, a command).
pub fn code(s: impl Into<String>) -> Span {
    Span::Code(s.into())
}

/// Emphasised text.
pub fn strong(s: impl Into<String>) -> Span {
    Span::Strong(s.into())
}

/// A link to `href` (relative to the page).
pub fn link(s: impl Into<String>, href: impl Into<String>) -> Span {
    Span::Link {
        text: s.into(),
        href: href.into(),
    }
}

/// How a status reads: good (`ok`, `completed`), worth reading (`warning`,
/// `pull_in`), or blocking (`ill_posed` … `failed`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tone {
    /// Nothing to report.
    Good,
    /// Usable, read the warnings.
    Caution,
    /// Not usable as it stands.
    Bad,
}

impl From<crate::fit::Status> for Tone {
    fn from(s: crate::fit::Status) -> Tone {
        match s {
            crate::fit::Status::Ok => Tone::Good,
            crate::fit::Status::Warning => Tone::Caution,
            _ => Tone::Bad,
        }
    }
}

impl From<crate::sim::RunStatus> for Tone {
    fn from(s: crate::sim::RunStatus) -> Tone {
        match s {
            crate::sim::RunStatus::Completed => Tone::Good,
            crate::sim::RunStatus::PullIn => Tone::Caution,
            crate::sim::RunStatus::Failed => Tone::Bad,
        }
    }
}

impl From<crate::rank::ranking::Status> for Tone {
    fn from(s: crate::rank::ranking::Status) -> Tone {
        use crate::rank::ranking::Status;
        match s {
            Status::Ok => Tone::Good,
            Status::Warning => Tone::Caution,
            Status::Incomplete | Status::Failed => Tone::Bad,
        }
    }
}

impl Tone {
    /// The tone of a status as every output spells it (`ok`, `completed`: good;
    /// `warning`, `pull_in`: caution; anything else: bad).
    pub fn of(word: &str) -> Tone {
        match word {
            "ok" | "completed" => Tone::Good,
            "warning" | "pull_in" => Tone::Caution,
            _ => Tone::Bad,
        }
    }

    fn class(self) -> &'static str {
        match self {
            Tone::Good => "good",
            Tone::Caution => "caution",
            Tone::Bad => "bad",
        }
    }
}

/// A table cell: its text and, in the HTML page, an optional link.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// The text.
    pub text: String,
    /// Link target relative to the page (HTML only; Markdown shows the text).
    pub href: Option<String>,
    /// A status shown coloured by its tone (HTML only).
    pub tone: Option<Tone>,
}

impl Cell {
    /// A cell of plain text.
    pub fn text(text: impl Into<String>) -> Cell {
        Cell {
            text: text.into(),
            href: None,
            tone: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Block {
    Status {
        word: String,
        tone: Tone,
    },
    Heading(String),
    Subheading(String),
    Paragraph(Vec<Span>),
    List(Vec<Vec<Span>>),
    Table {
        header: Vec<String>,
        rows: Vec<Vec<Cell>>,
    },
    Figure {
        file: String,
        alt: String,
        svg: String,
    },
}

/// A report page: a title and blocks in reading order.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    title: String,
    blocks: Vec<Block>,
    /// The `<meta>` element that says what kind of generated page this is (a
    /// folder's run list, [`super::runs`]; a project page), if any: only such an
    /// `index.html` is ever rebuilt.
    marker: Option<&'static str>,
}

impl Page {
    /// An empty page titled `title`.
    pub fn new(title: impl Into<String>) -> Page {
        Page {
            title: title.into(),
            blocks: Vec::new(),
            marker: None,
        }
    }

    /// The same page marked as a folder's run list (only such an `index.html` is
    /// ever rebuilt).
    pub(crate) fn run_list(self) -> Page {
        self.marked(runs::LIST_MARKER)
    }

    /// The same page carrying `marker` (a `<meta name="dea-fit-page" …>` element)
    /// in its head, which says what wrote it and may write it again.
    pub(crate) fn marked(mut self, marker: &'static str) -> Page {
        self.marker = Some(marker);
        self
    }

    /// The title.
    pub fn title(&self) -> &str {
        &self.title
    }

    /// The status of the page's run (the first status line), if it has one.
    pub fn status(&self) -> Option<&str> {
        self.blocks.iter().find_map(|b| match b {
            Block::Status { word, .. } => Some(word.as_str()),
            _ => None,
        })
    }

    /// The status line: "Status: **word**".
    pub fn status_line(&mut self, word: impl std::fmt::Display, tone: impl Into<Tone>) {
        self.blocks.push(Block::Status {
            word: word.to_string(),
            tone: tone.into(),
        });
    }

    /// A section heading.
    pub fn heading(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Heading(s.into()));
    }

    /// A heading inside a section.
    pub fn subheading(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Subheading(s.into()));
    }

    /// A paragraph of spans.
    pub fn para(&mut self, spans: Vec<Span>) {
        self.blocks.push(Block::Paragraph(spans));
    }

    /// A paragraph of plain text.
    pub fn text(&mut self, s: impl Into<String>) {
        self.para(vec![text(s)]);
    }

    /// A bulleted list; nothing when `items` is empty.
    pub fn list(&mut self, items: Vec<Vec<Span>>) {
        if !items.is_empty() {
            self.blocks.push(Block::List(items));
        }
    }

    /// A bulleted list of plain-text items; nothing when empty.
    pub fn bullets<S: Into<String>>(&mut self, items: impl IntoIterator<Item = S>) {
        self.list(items.into_iter().map(|s| vec![text(s)]).collect());
    }

    /// A "Warnings" section listing `warnings`; nothing when there are none.
    pub fn warnings(&mut self, warnings: &[String]) {
        if !warnings.is_empty() {
            self.heading("Warnings");
            self.bullets(warnings.iter().cloned());
        }
    }

    /// A table of text cells.
    pub fn table(&mut self, header: &[&str], rows: Vec<Vec<String>>) {
        self.linked_table(
            header,
            rows.into_iter()
                .map(|r| r.into_iter().map(Cell::text).collect())
                .collect(),
        );
    }

    /// A table whose cells may link (in HTML) to files beside the page.
    pub fn linked_table(&mut self, header: &[&str], rows: Vec<Vec<Cell>>) {
        self.blocks.push(Block::Table {
            header: header.iter().map(|h| h.to_string()).collect(),
            rows,
        });
    }

    /// Draw `chart` into `dir/file` (atomically) and show it here; `alt` describes it.
    pub fn chart(&mut self, dir: &Path, file: &str, alt: &str, chart: &Chart) -> Result<()> {
        let path = dir.join(file);
        let svg = chart.svg(&path)?;
        self.svg(dir, file, alt, svg)
    }

    /// Write the drawing `svg` into `dir/file` (atomically) and show it here.
    pub fn svg(&mut self, dir: &Path, file: &str, alt: &str, svg: String) -> Result<()> {
        atomic_write(&dir.join(file), svg.as_bytes())?;
        self.blocks.push(Block::Figure {
            file: file.into(),
            alt: alt.into(),
            svg,
        });
        Ok(())
    }

    /// The page as Markdown: figures linked (`![alt](file.svg)`), tables as aligned
    /// text in code blocks.
    pub fn markdown(&self) -> String {
        let mut s = format!("# {}\n", md_text(&self.title));
        for b in &self.blocks {
            s.push('\n');
            match b {
                Block::Status { word, .. } => {
                    let _ = writeln!(s, "Status: **{}**", md_text(word));
                }
                Block::Heading(h) => {
                    let _ = writeln!(s, "## {}", md_text(h));
                }
                Block::Subheading(h) => {
                    let _ = writeln!(s, "### {}", md_text(h));
                }
                Block::Paragraph(spans) => {
                    let _ = writeln!(s, "{}", md_spans(spans));
                }
                Block::List(items) => {
                    for i in items {
                        let _ = writeln!(s, "- {}", md_spans(i));
                    }
                }
                Block::Table { header, rows } => {
                    let _ = write!(s, "```\n{}```\n", text_table(header, rows));
                }
                Block::Figure { file, alt, .. } => {
                    let _ = writeln!(s, "![{}]({})", md_text(alt), href(file));
                }
            }
        }
        s
    }

    /// The page as plain text for a terminal, every line fitted to
    /// [`super::format::WIDTH`] ([`super::format::fit_width`]): the title, then the
    /// blocks in order — a status as `status: word`, a heading after a blank line,
    /// paragraphs as plain text, list items after "- ", tables aligned ([`table`]);
    /// figures are left out (they are files of the report).
    pub fn terminal(&self) -> String {
        let mut s = format!("{}\n", self.title);
        for b in &self.blocks {
            match b {
                Block::Status { word, .. } => {
                    let _ = writeln!(s, "status: {word}");
                }
                Block::Heading(h) | Block::Subheading(h) => {
                    let _ = write!(s, "\n{h}\n");
                }
                Block::Paragraph(spans) => {
                    let _ = writeln!(s, "{}", plain_spans(spans));
                }
                Block::List(items) => {
                    for i in items {
                        let _ = writeln!(s, "- {}", plain_spans(i));
                    }
                }
                Block::Table { header, rows } => s.push_str(&text_table(header, rows)),
                Block::Figure { .. } => {}
            }
        }
        super::format::fit_width(&s)
    }

    /// The page as one self-contained HTML document: the figures' SVG inline, the
    /// style sheet inline, no script and no external resource, so that it reads the
    /// same offline and as a mailed attachment. `markdown`: the name of the Markdown
    /// twin for the footer, if there is one.
    pub fn html(&self, markdown: Option<&str>) -> String {
        let mut s = String::with_capacity(64 * 1024);
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <meta name=\"generator\" content=\"{GENERATOR}\">\n{}<title>{}</title>\n\
             <style>\n{STYLE}</style>\n</head>\n<body>\n<main>\n<h1>{}</h1>\n",
            self.marker.map_or(String::new(), |m| format!("{m}\n")),
            esc(&self.title),
            esc(&self.title)
        );
        for b in &self.blocks {
            match b {
                Block::Status { word, tone } => {
                    let _ = writeln!(
                        s,
                        "<p class=\"status\">Status: <strong class=\"{}\">{}</strong></p>",
                        tone.class(),
                        esc(word)
                    );
                }
                Block::Heading(h) => {
                    let _ = writeln!(s, "<h2>{}</h2>", esc(h));
                }
                Block::Subheading(h) => {
                    let _ = writeln!(s, "<h3>{}</h3>", esc(h));
                }
                Block::Paragraph(spans) => {
                    let _ = writeln!(s, "<p>{}</p>", html_spans(spans));
                }
                Block::List(items) => {
                    s.push_str("<ul>\n");
                    for i in items {
                        let _ = writeln!(s, "<li>{}</li>", html_spans(i));
                    }
                    s.push_str("</ul>\n");
                }
                Block::Table { header, rows } => html_table(&mut s, header, rows),
                Block::Figure { alt, svg, .. } => {
                    let _ = writeln!(s, "<figure>\n{}\n</figure>", inline_svg(svg, alt));
                }
            }
        }
        let _ = write!(s, "<footer>Written by dea-fit {VERSION}");
        if let Some(md) = markdown {
            let _ = write!(
                s,
                "; the same page as Markdown: <code>{}</code>; the charts as SVG files beside it",
                esc(md)
            );
        }
        s.push_str(".</footer>\n</main>\n</body>\n</html>\n");
        s
    }

    /// Write `<stem>.md` and `<stem>.html` into `dir`, the run's metadata beside them
    /// ([`runs::meta_name`]), and refresh the run list of the folder holding `dir`
    /// ([`runs::refresh_index`]). Returns the HTML page's path.
    pub fn write(&self, dir: &Path, stem: &str, run: Run) -> Result<PathBuf> {
        let md = format!("{stem}.md");
        let html = dir.join(format!("{stem}.html"));
        atomic_write(&dir.join(&md), self.markdown().as_bytes())?;
        atomic_write(&html, self.html(Some(&md)).as_bytes())?;
        runs::record(dir, stem, self, run)?;
        Ok(html)
    }
}

/// Written into every page's `<meta name="generator">`.
const GENERATOR: &str = concat!("dea-fit ", env!("CARGO_PKG_VERSION"));
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The style sheet of every page: system fonts, bordered tables with numbers
/// right-aligned, figures no wider than the page, coloured status.
pub(crate) const STYLE: &str = "\
body{margin:0;background:#fff;color:#1b1b1b;font:16px/1.5 system-ui,-apple-system,\"Segoe UI\",Roboto,\"Noto Sans\",\"DejaVu Sans\",Arial,sans-serif}
main{max-width:80rem;margin:0 auto;padding:1.5rem 1.25rem 3rem}
h1{font-size:1.6rem;line-height:1.25;margin:0 0 .75rem}
h2{font-size:1.25rem;margin:2.2rem 0 .6rem;padding-bottom:.2rem;border-bottom:1px solid #d0d0d0}
h3{font-size:1.05rem;margin:1.6rem 0 .5rem}
p,li{max-width:52rem}
code{font-family:ui-monospace,\"DejaVu Sans Mono\",Menlo,Consolas,monospace;font-size:.88em;background:#f2f2f2;padding:0 .25em;border-radius:3px;overflow-wrap:anywhere}
a{color:#0b57a4}
.status{font-size:1.05rem}
.status strong,td strong{padding:.1em .55em;border-radius:4px}
.good{background:#e2f3df;color:#195e13}
.caution{background:#fff0c2;color:#654800}
.bad{background:#fbdede;color:#8c1111}
.scroll{overflow-x:auto;margin:.8rem 0 1.2rem}
table{border-collapse:collapse;font-size:.9rem}
th,td{border:1px solid #b9b9b9;padding:.25rem .55rem;text-align:left;vertical-align:top}
td{overflow-wrap:break-word}
th{background:#efefef;font-weight:600}
tbody tr:nth-child(even){background:#fafafa}
.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
td strong{white-space:nowrap}
figure{margin:1.2rem 0 1.8rem}
figure svg{display:block;max-width:100%;height:auto;border:1px solid #e3e3e3}
footer{margin-top:3rem;padding-top:.5rem;border-top:1px solid #d0d0d0;font-size:.85rem;color:#555}
@media print{main{max-width:none}figure,table{break-inside:avoid}}
";

/// `s` for HTML text and attribute values.
pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// A path relative to the page as a URL: each segment percent-encoded (a file name
/// with a space, `#` or `%` still links to itself).
pub fn href(path: &str) -> String {
    use percent_encoding::{utf8_percent_encode, AsciiSet, NON_ALPHANUMERIC};
    const SEGMENT: &AsciiSet = &NON_ALPHANUMERIC
        .remove(b'-')
        .remove(b'.')
        .remove(b'_')
        .remove(b'~');
    path.split('/')
        .map(|seg| utf8_percent_encode(seg, SEGMENT).to_string())
        .collect::<Vec<_>>()
        .join("/")
}

/// Markdown text with the characters that would start markup escaped: `\`, `` ` ``,
/// `*`, `[`, `]`, `<`, `>`, and `_` where it is not inside a word (an underscore
/// between letters, as in `mass_fraction`, never starts emphasis).
fn md_text(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut o = String::with_capacity(s.len());
    for (i, &c) in chars.iter().enumerate() {
        let word = |j: Option<usize>| {
            j.and_then(|j| chars.get(j))
                .is_some_and(|c| c.is_alphanumeric())
        };
        let escape = match c {
            '\\' | '`' | '*' | '[' | ']' | '<' | '>' => true,
            '_' => !(word(i.checked_sub(1)) && word(Some(i + 1))),
            _ => false,
        };
        if escape {
            o.push('\\');
        }
        o.push(c);
    }
    o
}

/// Code in Markdown: a backtick fence one longer than the longest run of backticks
/// inside, padded when the code starts or ends with one.
fn md_code(s: &str) -> String {
    let longest = s.split(|c| c != '`').map(str::len).max().unwrap_or(0);
    let fence = "`".repeat(longest + 1);
    let pad = if s.starts_with('`') || s.ends_with('`') {
        " "
    } else {
        ""
    };
    format!("{fence}{pad}{s}{pad}{fence}")
}

/// A table block as aligned text ([`table`]): the cells' text, links dropped.
fn text_table(header: &[String], rows: &[Vec<Cell>]) -> String {
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    let r: Vec<Vec<String>> = rows
        .iter()
        .map(|r| r.iter().map(|c| c.text.clone()).collect())
        .collect();
    table(&h, &r)
}

fn plain_spans(spans: &[Span]) -> String {
    spans
        .iter()
        .map(|sp| match sp {
            Span::Text(t) | Span::Code(t) | Span::Strong(t) => t.as_str(),
            Span::Link { text, .. } => text.as_str(),
        })
        .collect()
}

fn md_spans(spans: &[Span]) -> String {
    spans
        .iter()
        .map(|sp| match sp {
            Span::Text(t) => md_text(t),
            Span::Code(c) => md_code(c),
            Span::Strong(t) => format!("**{}**", md_text(t)),
            Span::Link { text, href: h } => format!("[{}]({})", md_text(text), href(h)),
        })
        .collect()
}

fn html_spans(spans: &[Span]) -> String {
    spans
        .iter()
        .map(|sp| match sp {
            Span::Text(t) => esc(t),
            Span::Code(c) => format!("<code>{}</code>", esc(c)),
            Span::Strong(t) => format!("<strong>{}</strong>", esc(t)),
            Span::Link { text, href: h } => {
                format!("<a href=\"{}\">{}</a>", esc(&href(h)), esc(text))
            }
        })
        .collect()
}

/// Whether a cell reads as a number (possibly with a unit, an interval, a
/// percentage) or a placeholder for one ("—", "n/a", empty).
fn numeric_cell(s: &str) -> Option<bool> {
    let t = s.trim();
    if t.is_empty() || t == "—" || t == "–" || t == "n/a" {
        return None;
    }
    let t = t.trim_start_matches(['[', '(', '-', '+', '−', '±', '#', ' ']);
    Some(t.starts_with(|c: char| c.is_ascii_digit() || c == '.') || t.starts_with("inf"))
}

fn html_table(s: &mut String, header: &[String], rows: &[Vec<Cell>]) {
    // A column reads as numbers when every cell that holds something does.
    let numeric: Vec<bool> = (0..header.len())
        .map(|j| {
            let cells: Vec<Option<bool>> = rows
                .iter()
                .map(|r| r.get(j).and_then(|c| numeric_cell(&c.text)))
                .collect();
            cells.iter().any(Option::is_some) && cells.iter().all(|c| c.unwrap_or(true))
        })
        .collect();
    let class = |j: usize| if numeric[j] { " class=\"num\"" } else { "" };
    s.push_str("<div class=\"scroll\"><table>\n<thead><tr>");
    for (j, h) in header.iter().enumerate() {
        let _ = write!(s, "<th{}>{}</th>", class(j), esc(h));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        s.push_str("<tr>");
        for (j, c) in r.iter().enumerate() {
            // A long path may break after any of its slashes.
            let shown = esc(&c.text).replace('/', "/<wbr>");
            let mut body = match &c.href {
                Some(h) => format!("<a href=\"{}\">{shown}</a>", esc(&href(h))),
                None => shown,
            };
            if let Some(t) = c.tone {
                body = format!("<strong class=\"{}\">{body}</strong>", t.class());
            }
            let _ = write!(s, "<td{}>{body}</td>", class(j.min(numeric.len() - 1)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table></div>\n");
}

/// An SVG drawing for inlining: any XML prologue dropped, and labelled for screen
/// readers (`role="img"`, `aria-label`).
fn inline_svg(svg: &str, alt: &str) -> String {
    let body = match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    };
    body.replacen(
        "<svg",
        &format!("<svg role=\"img\" aria-label=\"{}\"", esc(alt)),
        1,
    )
    .trim_end()
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_escapes_markup_but_not_word_underscores() {
        assert_eq!(
            md_text("a<b> *c* [d] mass_fraction _x_"),
            "a\\<b\\> \\*c\\* \\[d\\] mass_fraction \\_x\\_"
        );
        assert_eq!(md_code("a`b"), "``a`b``");
        assert_eq!(md_code("`x"), "`` `x ``");
    }

    #[test]
    fn hrefs_are_percent_encoded_per_segment() {
        assert_eq!(href("run 1/index.html"), "run%201/index.html");
        assert_eq!(href("a#b%/c.svg"), "a%23b%25/c.svg");
    }

    #[test]
    fn numbers_are_told_from_words() {
        for n in ["1.5 kPa", "-3", "−2.0e-3", "[1, 2]", "± 0.1", "#1", "12 %"] {
            assert_eq!(numeric_cell(n), Some(true), "{n}");
        }
        for w in ["yeoh", "ok", "no: at bound"] {
            assert_eq!(numeric_cell(w), Some(false), "{w}");
        }
        assert_eq!(numeric_cell("—"), None);
    }
}
