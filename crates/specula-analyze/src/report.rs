//! What every analysis's report folder shares: the style sheet and the writing of files and
//! plots. Each analysis writes its own folder (`report.html`, `report.json`, each plot as PNG
//! and SVG) in its own `report.rs`.

use std::path::Path;

use crate::figure::{png_bytes, Plot};
use crate::AnalyzeError;

/// The reports' shared style sheet.
pub(crate) const STYLE: &str = "
body { font-family: sans-serif; margin: 2em; background: #fafafa; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 4px 8px; text-align: right; }
td:first-child, th:first-child { text-align: left; }
figure { display: inline-block; margin: 0.5em; vertical-align: top; }
";

pub(crate) fn write_error(path: &Path, e: impl std::fmt::Display) -> AnalyzeError {
    AnalyzeError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

pub(crate) fn write(path: &Path, bytes: &[u8]) -> Result<(), AnalyzeError> {
    std::fs::write(path, bytes).map_err(|e| write_error(path, e))
}

pub(crate) fn write_plot(dir: &Path, name: &str, plot: &Plot) -> Result<(), AnalyzeError> {
    write(&dir.join(format!("{name}.png")), &png_bytes(&plot.png))?;
    write(&dir.join(format!("{name}.svg")), plot.svg.as_bytes())
}
