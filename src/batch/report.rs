//! The comparison report of a batch (`radray batch JOBS.toml --report report.html`): one self-contained
//! HTML page with a table of all jobs and, per job, the final image, the pure radiosity image, their
//! false-colour difference with the metrics of `compare`, a reference image where the job names one,
//! timings and stats. The images are PNGs in `<report>_files/` beside the page, with the linear EXRs
//! behind them; the page fetches nothing else (no scripts, no fonts, no network).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::compare::{self, Metrics};
use crate::film::Image;
use crate::output::{self, OutputError};
use crate::run::{Failure, PngSettings};
use crate::trace::whitted::TraceMode;

use super::manifest::JobRecord;

/// Where a report goes: the page, and the folder of its images beside it.
#[derive(Clone, Debug)]
pub struct ReportPaths {
    pub page: PathBuf,
    /// `<page stem>_files/`, beside the page.
    pub files: PathBuf,
}

impl ReportPaths {
    /// Checks that the page can be written and creates its image folder, before any job runs.
    pub fn prepare(page: &Path) -> Result<ReportPaths, Failure> {
        let ext = page.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("html" | "htm")) {
            return Err(Failure::input(anyhow::anyhow!("{}: --report must end in .html", page.display())));
        }
        crate::run::check_output_directory(page)?;
        let stem = page.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let files = page.with_file_name(format!("{stem}_files"));
        std::fs::create_dir_all(&files).map_err(|e| {
            Failure::input(anyhow::anyhow!("{}: cannot create the report's image folder: {e}", files.display()))
        })?;
        Ok(ReportPaths { page: page.to_path_buf(), files })
    }

    /// The name of the folder as the page links it.
    fn files_href(&self) -> String {
        self.files.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
    }

    /// The file of one job's image, `job-0007.final.exr`.
    pub fn image(&self, index: usize, what: &str, ext: &str) -> PathBuf {
        self.files.join(format!("job-{index:04}.{what}.{ext}"))
    }

    /// The outputs a job adds to its plan for the report: both modes, as linear EXR (for the metrics)
    /// and as PNG (for the page).
    pub fn plan(&self, index: usize) -> Vec<(TraceMode, PathBuf)> {
        let mut plan = Vec::new();
        for (mode, what) in [(TraceMode::Final, "final"), (TraceMode::Radiosity, "radiosity")] {
            for ext in ["exr", "png"] {
                plan.push((mode, self.image(index, what, ext)));
            }
        }
        plan
    }
}

/// Metrics of a test image against a reference (the fields of `compare --json` a report shows).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Comparison {
    #[serde(rename = "relMSE")]
    pub rel_mse: f64,
    pub mean_abs_rel_err: f64,
    pub rmse: f64,
    pub max_abs_diff: f64,
    /// Best-fit scale s minimising Σ (s·test − ref)².
    pub scale: f64,
    pub mean_test: f64,
    pub mean_ref: f64,
}

impl From<&Metrics> for Comparison {
    fn from(m: &Metrics) -> Self {
        Comparison {
            rel_mse: m.errors.rel_mse,
            mean_abs_rel_err: m.errors.mean_abs_rel_err,
            rmse: m.errors.rmse,
            max_abs_diff: m.max_abs_diff,
            scale: m.scale,
            mean_test: m.mean_test,
            mean_ref: m.mean_ref,
        }
    }
}

/// One job's part of the report, kept in its manifest record so that a resumed batch still reports
/// the jobs an earlier run finished. Image names are relative to the report's page.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct JobImages {
    pub final_png: String,
    pub radiosity_png: String,
    /// magma(max over channels |final − radiosity| / (|radiosity| + 0.01)), as `compare --diff`.
    pub difference_png: String,
    /// The final image against the pure radiosity image.
    pub final_vs_radiosity: Comparison,
    pub reference: Option<ReferenceImages>,
}

/// A job's reference and both images measured against it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReferenceImages {
    /// The reference file as the jobs file names it.
    pub source: String,
    pub reference_png: String,
    /// Set when the reference could not be compared (another size); then no metrics.
    pub error: Option<String>,
    pub final_difference_png: Option<String>,
    pub final_vs_reference: Option<Comparison>,
    pub radiosity_vs_reference: Option<Comparison>,
}

/// Reads a finished job's report images (written by the outputs `ReportPaths::plan` added), and writes
/// the difference images and the reference as PNGs with the job's exposure and tone curve.
pub fn job_images(
    paths: &ReportPaths,
    index: usize,
    png: &PngSettings,
    reference: Option<&Path>,
) -> Result<JobImages, OutputError> {
    let href = |path: PathBuf| {
        format!("{}/{}", paths.files_href(), path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default())
    };
    let final_image = output::read_image(&paths.image(index, "final", "exr"))?;
    let radiosity_image = output::read_image(&paths.image(index, "radiosity", "exr"))?;
    let (final_vs_radiosity, difference) = compared(&final_image, &radiosity_image)
        .map_err(|e| internal_size_error(&paths.image(index, "radiosity", "exr"), e))?;
    let difference_path = paths.image(index, "difference", "png");
    output::write_png(&difference, &difference_path, 0.0, output::ToneCurve::Clamp)?;
    let reference = match reference {
        None => None,
        Some(source) => {
            let reference_image = output::read_image(source)?;
            let reference_path = paths.image(index, "reference", "png");
            let stops = png.exposure.unwrap_or(output::Exposure::Stops(0.0)).stops_for(&final_image);
            output::write_png(&reference_image, &reference_path, stops, png.tone)?;
            let mut images = ReferenceImages {
                source: source.display().to_string(),
                reference_png: href(reference_path),
                error: None,
                final_difference_png: None,
                final_vs_reference: None,
                radiosity_vs_reference: None,
            };
            match (compared(&final_image, &reference_image), compare::metrics(&radiosity_image, &reference_image, None))
            {
                (Ok((final_metrics, final_difference)), Ok(radiosity_metrics)) => {
                    let path = paths.image(index, "reference_difference", "png");
                    output::write_png(&final_difference, &path, 0.0, output::ToneCurve::Clamp)?;
                    images.final_difference_png = Some(href(path));
                    images.final_vs_reference = Some(final_metrics);
                    images.radiosity_vs_reference = Some(Comparison::from(&radiosity_metrics));
                }
                (Err(e), _) | (_, Err(e)) => images.error = Some(format!("{}: {e}", source.display())),
            }
            Some(images)
        }
    };
    Ok(JobImages {
        final_png: href(paths.image(index, "final", "png")),
        radiosity_png: href(paths.image(index, "radiosity", "png")),
        difference_png: href(difference_path),
        final_vs_radiosity,
        reference,
    })
}

/// The metrics of `test` against `reference` and the false-colour difference image.
fn compared(test: &Image, reference: &Image) -> Result<(Comparison, Image), compare::CompareError> {
    let metrics = compare::metrics(test, reference, None)?;
    Ok((Comparison::from(&metrics), compare::difference_image(test, reference)?))
}

/// Both report images of a job come from one render of one scene, so a size mismatch is radray's bug.
fn internal_size_error(path: &Path, e: compare::CompareError) -> OutputError {
    OutputError::Read { path: path.to_path_buf(), source: std::io::Error::other(e.to_string()) }
}

/// Escapes text for HTML element content and quoted attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escapes a relative link: every byte outside unreserved characters and `/` is percent-encoded,
/// then the result is HTML-escaped (a no-op after the encoding).
fn escape_href(path: &str) -> String {
    let mut out = String::new();
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    escape(&out)
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;background:#fafafa}\
table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}\
th{background:#eee}td.text,th.text{text-align:left}.failed{color:#b00}\
section{border-top:2px solid #888;margin-top:1.5em;padding-top:0.5em}\
.images{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}\
figure img{width:256px;image-rendering:pixelated;border:1px solid #999;background:#000}\
figcaption{font-size:90%;max-width:256px}.stats td{font-size:85%}";

fn number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}

fn optional_number(x: Option<f64>) -> String {
    x.map_or_else(|| "—".to_string(), number)
}

/// The whole page for the batch's records (in job order); `title` is the jobs file.
pub fn page(title: &str, records: &[JobRecord]) -> String {
    let mut html = String::new();
    let failed = records.iter().filter(|r| r.status != "ok").count();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>radray batch: {t}</title>\n\
         <style>{STYLE}</style>\n</head>\n<body>\n<h1>radray batch: {t}</h1>\n\
         <p>{n} jobs, {failed} failed. Difference images show magma(max over channels |a − b| / (|b| + 0.01)): \
         black is equal, pale yellow is 100% or more.</p>\n",
        t = escape(title),
        n = records.len(),
    );
    summary_table(&mut html, records);
    for record in records {
        job_section(&mut html, record);
    }
    html.push_str("</body>\n</html>\n");
    html
}

fn summary_table(html: &mut String, records: &[JobRecord]) {
    html.push_str(
        "<table id=\"jobs\">\n<thead><tr><th>job</th><th class=\"text\">scene</th><th class=\"text\">status</th>\
         <th>seconds</th><th>elements</th><th>render s</th><th>relMSE final vs radiosity</th>\
         <th>relMSE final vs reference</th><th>relMSE radiosity vs reference</th></tr></thead>\n<tbody>\n",
    );
    for r in records {
        let images = r.report.as_ref();
        let reference = images.and_then(|i| i.reference.as_ref());
        let _ = writeln!(
            html,
            "<tr><td><a href=\"#job-{i}\">{i}</a></td><td class=\"text\">{scene}</td><td class=\"text{class}\">{status}</td>\
             <td>{seconds}</td><td>{elements}</td><td>{render}</td><td>{fr}</td><td>{fref}</td><td>{rref}</td></tr>",
            i = r.index,
            scene = escape(&r.scene),
            class = if r.status == "ok" { "" } else { " failed" },
            status = escape(&r.status),
            seconds = number(r.seconds),
            elements = r.stats.get("elements").map_or_else(|| "—".to_string(), |v| escape(&v.to_string())),
            render = optional_number(r.stats.get("render_seconds").and_then(|v| v.as_f64())),
            fr = optional_number(images.map(|i| i.final_vs_radiosity.rel_mse)),
            fref = optional_number(reference.and_then(|r| r.final_vs_reference.as_ref()).map(|c| c.rel_mse)),
            rref = optional_number(reference.and_then(|r| r.radiosity_vs_reference.as_ref()).map(|c| c.rel_mse)),
        );
    }
    html.push_str("</tbody>\n</table>\n");
}

fn figure(html: &mut String, href: &str, caption: &str) {
    let _ = writeln!(
        html,
        "<figure><img src=\"{src}\" alt=\"{c}\"><figcaption>{c}</figcaption></figure>",
        src = escape_href(href),
        c = escape(caption)
    );
}

fn comparison_row(html: &mut String, name: &str, c: &Comparison) {
    let _ = writeln!(
        html,
        "<tr><td class=\"text\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
        escape(name),
        number(c.rel_mse),
        number(c.mean_abs_rel_err),
        number(c.rmse),
        number(c.max_abs_diff),
        number(c.scale),
        number(c.mean_test),
        number(c.mean_ref),
    );
}

fn job_section(html: &mut String, r: &JobRecord) {
    let _ = writeln!(
        html,
        "<section id=\"job-{i}\">\n<h2>Job {i}: {scene}</h2>\n<p>Status: <span class=\"{class}\">{status}</span>, \
         {seconds} s. Outputs: {outputs}.</p>",
        i = r.index,
        scene = escape(&r.scene),
        class = if r.status == "ok" { "ok" } else { "failed" },
        status = escape(&r.status),
        seconds = number(r.seconds),
        outputs = if r.outputs.is_empty() { "none".to_string() } else { escape(&r.outputs.join(", ")) },
    );
    if let Some(error) = &r.error {
        let _ = writeln!(html, "<p class=\"failed\">{}</p>", escape(error));
    }
    if let Some(images) = &r.report {
        html.push_str("<div class=\"images\">\n");
        figure(html, &images.final_png, "final (two-pass)");
        figure(html, &images.radiosity_png, "pure radiosity");
        figure(html, &images.difference_png, "difference, final vs radiosity");
        if let Some(reference) = &images.reference {
            figure(html, &reference.reference_png, &format!("reference: {}", reference.source));
            if let Some(diff) = &reference.final_difference_png {
                figure(html, diff, "difference, final vs reference");
            }
        }
        html.push_str("</div>\n");
        html.push_str(
            "<table class=\"metrics\">\n<thead><tr><th class=\"text\">test vs reference</th><th>relMSE</th>\
             <th>mean abs rel err</th><th>RMSE</th><th>max abs diff</th><th>best scale</th><th>mean test</th>\
             <th>mean ref</th></tr></thead>\n<tbody>\n",
        );
        comparison_row(html, "final vs radiosity", &images.final_vs_radiosity);
        if let Some(reference) = &images.reference {
            if let Some(c) = &reference.final_vs_reference {
                comparison_row(html, "final vs reference", c);
            }
            if let Some(c) = &reference.radiosity_vs_reference {
                comparison_row(html, "radiosity vs reference", c);
            }
        }
        html.push_str("</tbody>\n</table>\n");
        if let Some(error) = images.reference.as_ref().and_then(|r| r.error.as_ref()) {
            let _ = writeln!(html, "<p class=\"failed\">reference not compared: {}</p>", escape(error));
        }
    }
    stats_table(html, r);
    html.push_str("</section>\n");
}

fn stats_table(html: &mut String, r: &JobRecord) {
    html.push_str("<table class=\"stats\">\n<tbody>\n");
    let _ = writeln!(
        html,
        "<tr><td class=\"text\">reused form factors / solution</td><td>{} / {}</td></tr>",
        r.reused_form_factors, r.reused_solution
    );
    if let Some(stats) = r.stats.as_object() {
        for (name, value) in stats {
            let shown = match value {
                serde_json::Value::String(text) => text.clone(),
                serde_json::Value::Number(n) if n.is_f64() => number(n.as_f64().unwrap_or(f64::NAN)),
                _ => value.to_string(),
            };
            let _ = writeln!(html, "<tr><td class=\"text\">{}</td><td>{}</td></tr>", escape(name), escape(&shown));
        }
    }
    html.push_str("</tbody>\n</table>\n");
}

/// Writes the page atomically.
pub fn write(paths: &ReportPaths, title: &str, records: &[JobRecord]) -> Result<(), Failure> {
    output::write_atomically(&paths.page, page(title, records).as_bytes())
        .map_err(|e| Failure::input(anyhow::anyhow!("{}: cannot write report: {e}", paths.page.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_leaves_no_markup() {
        assert_eq!(
            escape(r#"<script>alert("x & 'y'")</script>"#),
            "&lt;script&gt;alert(&quot;x &amp; &#39;y&#39;&quot;)&lt;/script&gt;"
        );
    }

    #[test]
    fn links_are_percent_encoded_then_escaped() {
        assert_eq!(escape_href("r_files/job-0001.final.png"), "r_files/job-0001.final.png");
        assert_eq!(escape_href("a b/\"<&>.png"), "a%20b/%22%3C%26%3E.png");
    }
}
