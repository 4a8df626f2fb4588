//! One policy for every figure option (`--plot`, `--waterfall`,
//! `--landscape`): the file name's extension decides the format, and a
//! name whose extension the option cannot write is refused before any work,
//! in one line naming the option and what it can write (issue 30: `decay
//! --plot d.png` wrote SVG into `d.png`). A name without an extension, and
//! a device, get the option's first format.

use crate::ReportError;
use std::path::Path;

/// A figure file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FigureFormat {
    Svg,
    Png,
    /// The figure's numbers (the landscape grid).
    Json,
}

impl FigureFormat {
    /// The extension, lower case, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            FigureFormat::Svg => "svg",
            FigureFormat::Png => "png",
            FigureFormat::Json => "json",
        }
    }
}

/// The format `flag` writes to `path`, from the extension (any case), if it
/// is one of `supported`; otherwise a one-line error naming the flag, the
/// file and the formats it can write.
pub fn figure_format(
    flag: &str,
    path: &Path,
    supported: &[FigureFormat],
) -> Result<FigureFormat, ReportError> {
    // a device (`/dev/null`, `/dev/stdout`) has no name to follow: the
    // option's first format is written through to it
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if let (Some(f), Ok(m)) = (supported.first(), std::fs::metadata(path)) {
            if m.file_type().is_char_device() {
                return Ok(*f);
            }
        }
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match (ext.as_deref(), supported.first()) {
        (None, Some(first)) => return Ok(*first),
        (Some(e), _) => {
            if let Some(f) = supported.iter().find(|f| f.extension() == e) {
                return Ok(*f);
            }
        }
        _ => {}
    }
    let names: Vec<String> = supported
        .iter()
        .map(|f| format!(".{}", f.extension()))
        .collect();
    let list = match names.len() {
        0 => String::new(),
        1 => names[0].clone(),
        n => format!("{} or {}", names[..n - 1].join(", "), names[n - 1]),
    };
    let upper: Vec<String> = supported
        .iter()
        .map(|f| f.extension().to_ascii_uppercase())
        .collect();
    Err(ReportError::Invalid(format!(
        "{flag} {}: this figure is written as {}; give a file name ending in {list}",
        path.display(),
        upper.join(" or ")
    )))
}

/// [`figure_format`] of an optional `path`.
pub fn check_figure(
    flag: &str,
    path: Option<&Path>,
    supported: &[FigureFormat],
) -> Result<Option<FigureFormat>, ReportError> {
    path.map(|p| figure_format(flag, p, supported)).transpose()
}

/// The formats of every line figure's `--plot`: SVG (the default, for a
/// name without an extension) or PNG, from the file name.
pub const PLOT_FORMATS: [FigureFormat; 2] = [FigureFormat::Svg, FigureFormat::Png];

/// The format of a `--plot FILE` line figure ([`PLOT_FORMATS`]), checked
/// before any work; None without the option.
pub fn check_plot_name(path: Option<&Path>) -> Result<Option<nlsdof_figure::Format>, ReportError> {
    Ok(
        check_figure("--plot", path, &PLOT_FORMATS)?.map(|f| match f {
            FigureFormat::Png => nlsdof_figure::Format::Png,
            _ => nlsdof_figure::Format::Svg,
        }),
    )
}

/// The format `path` asks for among SVG and PNG (for a figure rendered
/// after [`check_plot_name`] accepted the name): PNG for `.png`, else SVG.
pub fn plot_format(path: &Path) -> nlsdof_figure::Format {
    match check_figure("--plot", Some(path), &PLOT_FORMATS) {
        Ok(Some(FigureFormat::Png)) => nlsdof_figure::Format::Png,
        _ => nlsdof_figure::Format::Svg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use FigureFormat::*;

    #[test]
    fn the_extension_decides_and_others_are_refused() {
        let f = |p: &str, s: &[FigureFormat]| figure_format("--plot", Path::new(p), s);
        assert_eq!(f("a.svg", &[Svg]).unwrap(), Svg);
        assert_eq!(f("dir.v2/A.SVG", &[Svg]).unwrap(), Svg);
        assert_eq!(f("l.png", &[Json, Svg, Png]).unwrap(), Png);
        assert_eq!(f("d", &[Svg]).unwrap(), Svg);
        for bad in ["d.png", "d.svg.txt", "x.PDF"] {
            let e = f(bad, &[Svg]).unwrap_err().to_string();
            assert!(
                e.contains("written as SVG") && e.contains(".svg"),
                "{bad}: {e}"
            );
        }
        #[cfg(unix)]
        assert_eq!(f("/dev/null", &[Svg]).unwrap(), Svg);
        let e = f("x.pdf", &[Json, Svg, Png]).unwrap_err().to_string();
        assert!(e.contains(".json, .svg or .png"), "{e}");
    }
}
