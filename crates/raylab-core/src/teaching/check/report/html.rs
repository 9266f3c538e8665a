//! The class report's page, `index.html`: one file with its style, opened from the file system
//! (no server), whose links lead only to the report folder's images and to places in the page.
//!
//! At the top, a histogram of the verdicts (inline SVG); then a row a submission: its
//! thumbnail, the exact figure's, the difference amplified, the verdict with its fix, the share
//! of pixels within 2/255, the SSIM and the worst region. Without JavaScript: filtering by
//! verdict (radio buttons whose `:checked` hides the other rows) and a detail view a student
//! (a section shown by `:target`: the full-size images, the worst region outlined, and an A/B
//! wipe whose divider is the corner of a box the browser lets one resize). With JavaScript,
//! the columns also sort.

use std::fmt::Write as _;

use super::{figure_files, row_files, row_id, verdict_counts, verdict_order, worst_region};
use crate::teaching::check::class::{Class, REFUSED, Row};
use crate::teaching::check::compare::{DIFF_GAIN, TOLERANCE};
use crate::teaching::check::{RIGHT, WELL};

/// `text` with `&`, `<`, `>`, `"` and `'` escaped, for text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// How a verdict is named on the page.
fn verdict_label(verdict: &str) -> String {
    match verdict {
        "none" => "right".to_owned(),
        REFUSED => "not checked".to_owned(),
        other => other.to_owned(),
    }
}

/// The colour a verdict is drawn in: right green, a named mistake amber, unknown slate,
/// refused red.
fn verdict_colour(verdict: &str) -> &'static str {
    match verdict {
        "none" => "#2e7d32",
        "unknown" => "#546e7a",
        REFUSED => "#c62828",
        _ => "#b26a00",
    }
}

/// A verdict's place when sorting: its place in [`verdict_order`] (a verdict not listed goes
/// with unknown).
fn verdict_rank(verdict: &str) -> usize {
    let order = verdict_order();
    let place = |v: &str| order.iter().position(|o| *o == v);
    place(verdict).or_else(|| place("unknown")).unwrap_or(0)
}

fn percent(share: f64) -> String {
    format!("{:.1} %", 100.0 * share)
}

const STYLE: &str = r#"
:root { color-scheme: light; --ink: #1d2327; --muted: #5f6b73; --line: #dde3e8; }
* { box-sizing: border-box; }
body { margin: 0; font: 14px/1.45 system-ui, -apple-system, "Segoe UI", "DejaVu Sans", sans-serif; color: var(--ink); background: #f6f8fa; }
header { padding: 20px 28px 8px; background: #fff; border-bottom: 1px solid var(--line); }
h1 { font-size: 22px; margin: 0 0 4px; }
h2 { font-size: 18px; margin: 0 0 8px; }
.muted, small { color: var(--muted); }
.top { display: flex; flex-wrap: wrap; gap: 28px; align-items: flex-start; }
.top > div { flex: 1 1 380px; min-width: 0; }
.against { list-style: none; padding: 0; margin: 8px 0; }
.against li { display: flex; gap: 10px; align-items: center; margin: 4px 0; }
.against img { width: 48px; height: auto; border: 1px solid var(--line); }
main { padding: 12px 28px 40px; }
.show { position: absolute; opacity: 0; pointer-events: none; }
.filters { display: flex; flex-wrap: wrap; gap: 6px; margin: 4px 0 12px; align-items: center; }
.filters label { cursor: pointer; padding: 3px 10px; border-radius: 14px; border: 1px solid var(--line); background: #fff; }
.filters label::before { content: ""; display: inline-block; width: 9px; height: 9px; border-radius: 50%; margin-right: 6px; background: var(--c, #90a4ae); }
.show:focus-visible + * { outline: 2px solid #1565c0; }
table { border-collapse: collapse; width: 100%; background: #fff; border: 1px solid var(--line); }
th, td { padding: 6px 8px; border-bottom: 1px solid var(--line); text-align: left; vertical-align: top; }
th { background: #eef2f5; font-weight: 600; white-space: nowrap; position: sticky; top: 0; z-index: 1; }
th[data-key] { cursor: pointer; }
th[data-dir="asc"]::after { content: " ▲"; } th[data-dir="desc"]::after { content: " ▼"; }
td.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
td.pic img { display: block; width: 80px; height: auto; border: 1px solid var(--line); background: #000; }
td.name { min-width: 11em; overflow-wrap: anywhere; }
td.name a { font-weight: 600; color: #0d47a1; text-decoration: none; }
.verdict { font-weight: 700; }
.fix { display: block; max-width: 38em; }
.flag { display: inline-block; margin-top: 4px; padding: 1px 6px; border-radius: 4px; background: #fdecea; color: #b71c1c; font-size: 12px; }
.note { display: block; color: var(--muted); font-size: 12px; max-width: 38em; }
.detail { display: none; }
.detail:target { display: block; position: fixed; inset: 0; z-index: 5; overflow: auto; background: rgba(20, 26, 31, 0.72); padding: 24px; }
.sheet { background: #fff; max-width: 1180px; margin: 0 auto; padding: 20px 24px 28px; border-radius: 8px; }
.close { float: right; font-size: 15px; text-decoration: none; color: #0d47a1; }
.pics { display: flex; flex-wrap: wrap; gap: 24px; margin-top: 14px; }
.pics figure { margin: 0; }
.pics figcaption { color: var(--muted); font-size: 12px; margin-top: 4px; }
.wipe, .marked { position: relative; line-height: 0; background: #000; }
.wipe img, .marked img { display: block; max-width: none; }
.px { image-rendering: pixelated; }
.over { position: absolute; top: 0; left: 0; height: 100%; width: 50%; min-width: 12px; max-width: 100%; overflow: hidden; resize: horizontal; border-right: 2px solid #fff; box-shadow: 2px 0 0 rgba(0,0,0,.35); }
.over::after { content: "A | B"; position: absolute; right: 4px; top: 4px; font: 11px/1 system-ui, sans-serif; color: #fff; background: rgba(0,0,0,.55); padding: 2px 4px; border-radius: 3px; }
.box { position: absolute; border: 2px solid #ffeb3b; box-shadow: 0 0 0 1px #000; }
.numbers { width: auto; border: 0; margin: 8px 0; background: none; }
.numbers td, .numbers th { border: 0; padding: 2px 14px 2px 0; background: none; position: static; }
.candidates { margin-top: 12px; }
"#;

/// Sorting by a column: a click on a heading with a `data-key` orders the rows by their
/// `data-KEY` values (numbers as numbers), and again the other way. A page opened at
/// `#sort-KEY` (or `#sort-KEY-desc`) starts sorted so.
const SCRIPT: &str = r##"
function sortBy(th, dir) {
  var key = th.dataset.key, body = document.querySelector("#class tbody");
  document.querySelectorAll("th[data-key]").forEach(function (h) { delete h.dataset.dir; });
  th.dataset.dir = dir;
  var rows = Array.prototype.slice.call(body.rows);
  rows.sort(function (a, b) {
    var x = a.dataset[key], y = b.dataset[key], nx = parseFloat(x), ny = parseFloat(y);
    var c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : x.localeCompare(y);
    return dir === "asc" ? c : -c;
  });
  rows.forEach(function (r) { body.appendChild(r); });
}
document.querySelectorAll("th[data-key]").forEach(function (th) {
  th.tabIndex = 0;
  th.title = "Sort by this column";
  function flip() { sortBy(th, th.dataset.dir === "asc" ? "desc" : "asc"); }
  th.addEventListener("click", flip);
  th.addEventListener("keydown", function (e) { if (e.key === "Enter" || e.key === " ") { e.preventDefault(); flip(); } });
});
var asked = /^#sort-(\w+?)(-desc)?$/.exec(location.hash);
var heading = asked && document.querySelector('th[data-key="' + asked[1] + '"]');
if (heading) { sortBy(heading, asked[2] ? "desc" : "asc"); }
"##;

/// The histogram of verdicts as an SVG: a bar a verdict, its count after it.
fn histogram(counts: &[(String, usize)]) -> String {
    let bar_height = 20;
    let gap = 6;
    let label_width = 170;
    let bar_width = 300;
    let width = label_width + bar_width + 50;
    let height = counts.len().max(1) * (bar_height + gap) + gap;
    let most = counts.iter().map(|(_, n)| *n).max().unwrap_or(1).max(1);
    let mut svg = format!(
        "<svg class=\"histogram\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" \
         height=\"{height}\" viewBox=\"0 0 {width} {height}\" role=\"img\" \
         aria-label=\"Verdicts across the class\">"
    );
    for (i, (verdict, n)) in counts.iter().enumerate() {
        let y = gap + i * (bar_height + gap);
        let w = (bar_width * n).div_ceil(most).max(2);
        let label = escape(&verdict_label(verdict));
        let _ = write!(
            svg,
            "<g><title>{label}: {n}</title>\
             <text x=\"{lx}\" y=\"{ty}\" text-anchor=\"end\" font-size=\"13\" \
             fill=\"#1d2327\">{label}</text>\
             <rect x=\"{label_width}\" y=\"{y}\" width=\"{w}\" height=\"{bar_height}\" rx=\"3\" \
             fill=\"{colour}\"/>\
             <text x=\"{nx}\" y=\"{ty}\" font-size=\"13\" fill=\"#1d2327\">{n}</text></g>",
            lx = label_width - 8,
            ty = y + 15,
            nx = label_width + w + 6,
            colour = verdict_colour(verdict),
        );
    }
    svg.push_str("</svg>");
    svg
}

/// An `<img>` of a report image, `width` pixels wide on the page (`lazy`: loaded when shown).
fn img(src: &str, alt: &str, width: u32, height: u32, class: &str) -> String {
    format!(
        "<img src=\"{}\" alt=\"{}\" width=\"{width}\" height=\"{height}\" loading=\"lazy\"{}>",
        escape(src),
        escape(alt),
        if class.is_empty() {
            String::new()
        } else {
            format!(" class=\"{class}\"")
        }
    )
}

/// The table's row for submission `i`.
fn table_row(i: usize, row: &Row) -> String {
    let id = row_id(i);
    let name = escape(&row.submission.name);
    let verdict = row.verdict();
    let mut t = format!(
        "<tr id=\"r-{id}\" class=\"v-{verdict}\" data-name=\"{name}\" data-verdict=\"{rank}\" \
         data-match=\"{m}\" data-ssim=\"{s}\">",
        rank = verdict_rank(verdict),
        m = row.result.as_ref().map_or(-1.0, |j| j.report.match_share),
        s = row.result.as_ref().map_or(-1.0, |j| j.ssim),
    );
    let flag = if row.identical_to.is_empty() {
        String::new()
    } else {
        format!(
            "<span class=\"flag\">identical to {}</span>",
            escape(&row.identical_to.join(", "))
        )
    };
    match &row.result {
        Ok(j) => {
            let r = &j.report;
            let files = row_files(i);
            let (_, figure_thumb) = figure_files(row.against.unwrap_or(0));
            let [w, h] = r.size;
            let th = |src: &str, alt: &str| {
                format!(
                    "<td class=\"pic\"><a href=\"#d-{id}\">{}</a></td>",
                    img(src, alt, 80, (80 * h).div_ceil(w.max(1)), "")
                )
            };
            let _ = write!(
                t,
                "<td class=\"name\"><a href=\"#d-{id}\">{name}</a><br><small>{student}</small>\
                 {flag}</td>{a}{b}{c}",
                student = escape(&row.submission.student),
                a = th(&files.thumbnail, "the submission"),
                b = th(&figure_thumb, "the exact figure"),
                c = th(&files.difference_thumbnail, "the difference, amplified"),
            );
            let fix = if r.best.fix.is_empty() {
                String::new()
            } else {
                format!("<span class=\"fix\">{}</span>", escape(&r.best.fix))
            };
            let what = match r.best.what() {
                w if w.is_empty() => String::new(),
                w => format!(": {}", escape(&w)),
            };
            let notes: String = r
                .notes
                .iter()
                .map(|n| format!("<span class=\"note\">{}</span>", escape(n)))
                .collect();
            let _ = write!(
                t,
                "<td><span class=\"verdict\" style=\"color:{colour}\">{label}</span>{what}{fix}\
                 {notes}</td><td class=\"num\">{m}</td><td class=\"num\">{s:.3}</td>\
                 <td>{region}</td>",
                colour = verdict_colour(verdict),
                label = escape(&verdict_label(verdict)),
                m = percent(r.match_share),
                s = j.ssim,
                region = escape(&worst_region(row)),
            );
        }
        Err(reason) => {
            let _ = write!(
                t,
                "<td class=\"name\">{name}<br><small>{student}</small>{flag}</td>\
                 <td class=\"pic\"></td><td class=\"pic\"></td><td class=\"pic\"></td>\
                 <td><span class=\"verdict\" style=\"color:{colour}\">not checked</span>\
                 <span class=\"fix\">{reason}</span></td><td class=\"num\">—</td>\
                 <td class=\"num\">—</td><td></td>",
                student = escape(&row.submission.student),
                colour = verdict_colour(REFUSED),
                reason = escape(reason),
            );
        }
    }
    t.push_str("</tr>\n");
    t
}

/// The detail section of submission `i` (checked ones only).
fn detail(class: &Class, i: usize, row: &Row) -> String {
    let Ok(j) = &row.result else {
        return String::new();
    };
    let r = &j.report;
    let id = row_id(i);
    let files = row_files(i);
    let k = row.against.unwrap_or(0);
    let (figure, _) = figure_files(k);
    let [w, h] = r.size;
    // Small images are shown larger, pixel for pixel, so at least 320 pixels wide.
    let zoom = 320u32.div_ceil(w.max(h)).max(1);
    let (dw, dh) = (w * zoom, h * zoom);
    let px = if zoom > 1 { "px" } else { "" };
    let verdict = row.verdict();
    let mut t = format!(
        "<section class=\"detail\" id=\"d-{id}\" aria-label=\"{name}\"><div class=\"sheet\">\
         <a class=\"close\" href=\"#r-{id}\">✕ Back to the class</a><h2>{name}</h2>",
        name = escape(&row.submission.name)
    );
    let verdict_line = match verdict {
        "none" => "right: the image is the exact figure".to_owned(),
        "unknown" => "unknown: no classic mistake explains it".to_owned(),
        m => format!("{m}: {}", r.best.what()),
    };
    let _ = write!(
        t,
        "<p><span class=\"verdict\" style=\"color:{colour}\">{v}</span></p>",
        colour = verdict_colour(verdict),
        v = escape(&verdict_line),
    );
    if !r.best.equation.is_empty() {
        let _ = write!(
            t,
            "<p><b>Lab:</b> {}<br><b>Fix:</b> {}</p>",
            escape(&r.best.equation),
            escape(&r.best.fix)
        );
    } else if !r.best.fix.is_empty() {
        let _ = write!(t, "<p>{}</p>", escape(&r.best.fix));
    }
    for note in &r.notes {
        let _ = write!(t, "<p class=\"note\">{}</p>", escape(note));
    }
    if !row.identical_to.is_empty() {
        let _ = write!(
            t,
            "<p><span class=\"flag\">its pixels are identical to {}</span></p>",
            escape(&row.identical_to.join(", "))
        );
    }
    let settings = &class.against[k];
    let _ = write!(
        t,
        "<table class=\"numbers\"><tr><td>within 2/255 of the figure</td><td>{m}</td></tr>\
         <tr><td>with anti-aliased edges allowed for</td><td>{e}</td></tr>\
         <tr><td>SSIM (1 = no visible difference)</td><td>{s:.4}</td></tr>\
         <tr><td>worst region</td><td>{region}</td></tr>\
         <tr><td>checked against</td><td>{against}</td></tr></table>",
        m = percent(r.match_share),
        e = percent(r.with_edges),
        s = j.ssim,
        region = escape(&worst_region(row)),
        against = escape(&settings.summary()),
    );
    // The A/B wipe: the submission over the figure, cut at the right edge of a box the
    // reader resizes by its corner.
    let _ = write!(
        t,
        "<div class=\"pics\"><figure style=\"width:{dw}px\"><div class=\"wipe\" style=\"width:{dw}px;height:{dh}px\">\
         {under}<div class=\"over\">{over}</div></div><figcaption>A | B: left of the line the \
         submission, right of it the exact figure. Drag the corner at the foot of the line \
         (◢) to move it.</figcaption></figure>",
        under = img(&figure, "the exact figure", dw, dh, px),
        over = img(&files.image, "the submission", dw, dh, px),
    );
    let boxed = match &r.worst_block {
        Some(b) if b.mean_difference > 0.0 => format!(
            "<div class=\"box\" style=\"left:{}px;top:{}px;width:{}px;height:{}px\"></div>",
            b.x0 * zoom,
            b.y0 * zoom,
            (b.x1 - b.x0) * zoom,
            (b.y1 - b.y0) * zoom
        ),
        _ => String::new(),
    };
    let _ = write!(
        t,
        "<figure style=\"width:{dw}px\"><div class=\"marked\" style=\"width:{dw}px;height:{dh}px\">{diff}{boxed}</div>\
         <figcaption>|submission − figure| per channel, ×{DIFF_GAIN} (less where that would be white \
         nearly everywhere: the largest difference white): black where they agree; \
         the worst {b}-pixel block outlined.</figcaption></figure></div>",
        diff = img(&files.difference, "the difference, amplified", dw, dh, px),
        b = crate::teaching::check::compare::BLOCK,
    );
    if !r.candidates.is_empty() {
        t.push_str(
            "<table class=\"numbers candidates\"><tr><th>mistake</th><th>its figure explains</th>\
             </tr>",
        );
        for c in r.candidates.iter().take(6) {
            let _ = write!(
                t,
                "<tr><td>{}</td><td>{}</td></tr>",
                c.mistake.name(),
                percent(c.explains)
            );
        }
        t.push_str("</table>");
    }
    t.push_str("</div></section>\n");
    t
}

/// The page.
pub fn page(class: &Class, title: &str) -> String {
    let counts = verdict_counts(class);
    let total = class.rows.len();
    let checked = class.rows.iter().filter(|r| r.result.is_ok()).count();
    let right = counts
        .iter()
        .find(|(v, _)| v == "none")
        .map_or(0, |(_, n)| *n);
    let mut t = String::new();
    let _ = write!(
        t,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title} — raylab check</title><style>{STYLE}",
        title = escape(title)
    );
    // Filtering: the rule of each verdict's radio button hides the other rows.
    for (verdict, _) in &counts {
        let _ = write!(
            t,
            "#show-{verdict}:checked ~ table tbody tr:not(.v-{verdict}) {{ display: none; }}\n\
             #show-{verdict}:checked ~ .filters label[for=\"show-{verdict}\"] {{ \
             background: #e3ecf5; border-color: #1565c0; }}\n"
        );
    }
    t.push_str(
        "#show-all:checked ~ .filters label[for=\"show-all\"] { background: #e3ecf5; \
         border-color: #1565c0; }\n</style></head><body>\n",
    );
    let _ = write!(
        t,
        "<header><h1>{title}</h1><p class=\"muted\">{total} submissions: {right} right, \
         {wrong} with a difference, {refused} not checked. A pixel matches when each channel \
         is within {TOLERANCE}/255 of the exact figure's; an image is right when {r} of its \
         pixels match, and a mistake is named when its figure explains {w} of them. SSIM \
         ranks how visible a difference is.</p><div class=\"top\">{svg}<div><b>Checked \
         against</b><ul class=\"against\">",
        title = escape(title),
        wrong = checked - right,
        refused = total - checked,
        r = percent(RIGHT),
        w = percent(WELL),
        svg = histogram(&counts),
    );
    for (k, settings) in class.against.iter().enumerate() {
        let (figure, thumb) = figure_files(k);
        let stage = settings.shading.stage;
        let label = stage.figure().map_or(format!("stage {stage}"), |f| {
            format!("figure {f} (stage {stage})")
        });
        let used = class.rows.iter().filter(|r| r.against == Some(k)).count();
        let _ = write!(
            t,
            "<li><a href=\"{figure}\">{img}</a><span>{label}, {w}×{h}: {used} \
             submission{plural}<br><small>{summary}</small></span></li>",
            plural = if used == 1 { "" } else { "s" },
            img = img(&thumb, "the exact figure", 48, 48, ""),
            label = escape(&label),
            w = settings.camera.width,
            h = settings.camera.height,
            summary = escape(&settings.summary()),
        );
    }
    t.push_str("</ul></div></div></header>\n<main>\n");
    // The radio buttons come first: the filters' rules select the table after them.
    t.push_str("<input type=\"radio\" name=\"show\" class=\"show\" id=\"show-all\" checked>\n");
    for (verdict, _) in &counts {
        let _ = writeln!(
            t,
            "<input type=\"radio\" name=\"show\" class=\"show\" id=\"show-{verdict}\">"
        );
    }
    let _ = write!(
        t,
        "<nav class=\"filters\" aria-label=\"Show\"><b>Show:</b> <label for=\"show-all\">all \
         ({total})</label>"
    );
    for (verdict, n) in &counts {
        let _ = write!(
            t,
            "<label for=\"show-{verdict}\" style=\"--c:{c}\">{label} ({n})</label>",
            c = verdict_colour(verdict),
            label = escape(&verdict_label(verdict)),
        );
    }
    t.push_str(
        "<noscript><small>(sorting needs JavaScript; filtering and the details do not)</small>\
         </noscript></nav>\n",
    );
    t.push_str(
        "<table id=\"class\"><thead><tr><th data-key=\"name\">Submission</th><th>Image</th>\
         <th>Figure</th><th>Difference</th><th data-key=\"verdict\">Verdict</th>\
         <th data-key=\"match\">Match</th><th data-key=\"ssim\">SSIM</th><th>Worst region</th>\
         </tr></thead><tbody>\n",
    );
    for (i, row) in class.rows.iter().enumerate() {
        t.push_str(&table_row(i, row));
    }
    t.push_str("</tbody></table>\n</main>\n");
    for (i, row) in class.rows.iter().enumerate() {
        t.push_str(&detail(class, i, row));
    }
    let _ = write!(t, "<script>{SCRIPT}</script>\n</body></html>\n");
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::teaching::check::{FACTOR, OTHER_STAGE};

    #[test]
    fn text_is_escaped() {
        assert_eq!(
            escape("<a href=\"x\">Tom & Jerry's</a>"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; Jerry&#39;s&lt;/a&gt;"
        );
    }

    /// Right first, the mistakes in the catalogue's order, then another stage, a factor,
    /// unknown and refused.
    #[test]
    fn verdicts_sort_in_the_catalogues_order() {
        let ranks: Vec<usize> = [
            "none",
            "no-4pi",
            "bgr",
            OTHER_STAGE,
            FACTOR,
            "unknown",
            REFUSED,
        ]
        .map(verdict_rank)
        .to_vec();
        assert!(ranks.is_sorted(), "{ranks:?}");
        assert_eq!(ranks[0], 0);
    }
}
