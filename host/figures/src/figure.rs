//! Figure files of every stiffwall figure: the format by extension, one writer for both.
//!
//! Units: sizes in pixels. Invariants: the format is chosen by the file's extension, `.svg` or
//! `.png` in any case (`.SVG`, `.Png`); any other name is refused before anything is drawn,
//! with an error naming the path and the allowed extensions. The file is presented (written)
//! exactly once, after the whole figure is drawn. [`prepare`] checks the name and that the
//! file can be written before a long run starts (an existing file is left unchanged, a file
//! created by the check is removed). With the environment variable
//! [`crate::describe::TEXT_ENV`] set (to anything), [`write`] also writes `<file>.txt`, the
//! figure's [`Description`] as text (the gallery's font-independent record).

use crate::describe::Description;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// File format of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics (bitmap).
    Png,
}

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The file name does not end in an allowed extension.
    #[error("figure file '{}' must end in .svg or .png (any case)", .path.display())]
    Extension {
        /// The refused path.
        path: PathBuf,
    },
    /// The file cannot be created or written.
    #[error("cannot write the figure file '{}': {source}", .path.display())]
    Unwritable {
        /// The refused path.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Drawing or writing the file failed.
    #[error("writing the figure {}: {source}", .path.display())]
    Draw {
        /// The figure's path.
        path: PathBuf,
        /// What failed.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

/// What a drawing function returns on failure: plotters' backend error or a message.
pub type DrawError = Box<dyn std::error::Error + Send + Sync>;

/// The result of a drawing function.
pub type DrawResult<T = ()> = Result<T, DrawError>;

/// Something that can draw itself on any plotters backend and say what it draws.
pub trait Figure {
    /// The figure's words: title, axis labels, legend entries and key values, as drawn.
    fn describe(&self) -> Description;

    /// Draws the whole figure into `root` (which it fills); the writer presents it.
    ///
    /// # Errors
    /// A drawing error.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// The format of `path` by its extension (case-insensitive).
///
/// # Errors
/// [`FigureError::Extension`] for any other name.
pub fn format_of(path: &Path) -> Result<Format, FigureError> {
    let ext = path.extension().and_then(|e| e.to_str());
    match ext {
        Some(e) if e.eq_ignore_ascii_case("svg") => Ok(Format::Svg),
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(Format::Png),
        _ => Err(FigureError::Extension {
            path: path.to_path_buf(),
        }),
    }
}

/// Checks that `path` (any output file) can be written, leaving the file system as it was:
/// an existing file is opened for appending and left unchanged, a missing one is created and
/// removed again.
///
/// # Errors
/// The error of opening or creating the file (missing directory, no permission, a directory).
pub fn check_writable(path: &Path) -> std::io::Result<()> {
    if path.exists() {
        std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map(drop)
    } else {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)?;
        std::fs::remove_file(path)
    }
}

/// [`format_of`] and [`check_writable`]: call before a long computation.
///
/// # Errors
/// [`FigureError::Extension`] or [`FigureError::Unwritable`], naming the path.
pub fn prepare(path: &Path) -> Result<Format, FigureError> {
    let format = format_of(path)?;
    check_writable(path).map_err(|source| FigureError::Unwritable {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(format)
}

/// Draws `figure` at `size_px` (width, height) into `path`, SVG or PNG by extension.
///
/// # Errors
/// An unsupported extension, or a drawing or file error (naming the path).
pub fn write<F: Figure + ?Sized>(
    path: &Path,
    size_px: (u32, u32),
    figure: &F,
) -> Result<(), FigureError> {
    let draw_err = |source: DrawError| FigureError::Draw {
        path: path.to_path_buf(),
        source,
    };
    let drawn = match format_of(path)? {
        Format::Svg => render(SVGBackend::new(path, size_px).into_drawing_area(), figure),
        Format::Png => render(
            BitMapBackend::new(path, size_px).into_drawing_area(),
            figure,
        ),
    };
    drawn.map_err(draw_err)?;
    if std::env::var_os(crate::describe::TEXT_ENV).is_some() {
        let mut name = path.as_os_str().to_owned();
        name.push(".txt");
        let text_path = PathBuf::from(name);
        std::fs::write(&text_path, figure.describe().render()).map_err(|source| {
            FigureError::Unwritable {
                path: text_path,
                source,
            }
        })?;
    }
    Ok(())
}

fn render<DB: DrawingBackend, F: Figure + ?Sized>(
    root: DrawingArea<DB, Shift>,
    figure: &F,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    figure.draw(&root)?;
    root.present()?;
    Ok(())
}

/// What is wrong with `figure` drawn at `size` px: the [`Description::problems`] and every
/// title, axis label and legend entry of the description that the drawn SVG does not show.
///
/// # Errors
/// A drawing error.
pub fn audit<F: Figure>(
    figure: &F,
    size: (u32, u32),
    rotational: Option<bool>,
) -> DrawResult<Vec<String>> {
    let d = figure.describe();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        figure.draw(&root)?;
        root.present()?;
    }
    let text = crate::describe::svg_text(&svg);
    let mut out = d.problems(rotational);
    let drawn = d
        .axes
        .iter()
        .chain(&d.legend)
        .chain(std::iter::once(&d.title));
    for want in drawn {
        if !text.contains(want.as_str()) {
            out.push(format!("not drawn: '{want}'"));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Square;
    impl Figure for Square {
        fn describe(&self) -> Description {
            Description::new("square")
        }
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
        where
            DB::ErrorType: 'static,
        {
            root.fill(&WHITE)?;
            root.draw(&Rectangle::new([(2, 2), (8, 8)], RED.filled()))?;
            Ok(())
        }
    }

    struct Broken;
    impl Figure for Broken {
        fn describe(&self) -> Description {
            Description::new("broken")
        }
        fn draw<DB: DrawingBackend>(&self, _: &DrawingArea<DB, Shift>) -> DrawResult
        where
            DB::ErrorType: 'static,
        {
            Err("no data to draw".into())
        }
    }

    #[test]
    fn extension_picks_the_format_in_any_case() {
        for (name, want) in [
            ("a.svg", Format::Svg),
            ("a.SVG", Format::Svg),
            ("dir.png/a.Svg", Format::Svg),
            ("a.png", Format::Png),
            ("a.PNG", Format::Png),
            ("a.pNg", Format::Png),
        ] {
            assert_eq!(format_of(Path::new(name)).unwrap(), want, "{name}");
        }
    }

    #[test]
    fn other_names_are_refused_naming_path_and_extensions() {
        for name in ["a.jpg", "a", "a.svg.gz", "svg", ".png.txt"] {
            let e = format_of(Path::new(name)).unwrap_err().to_string();
            assert!(e.contains(&format!("'{name}'")), "{e}");
            assert!(e.contains(".svg or .png"), "{e}");
        }
    }

    #[test]
    fn writes_svg_and_png_by_extension_and_nothing_for_other_names() {
        let dir = std::env::temp_dir().join(format!("stiffwall-figure-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let svg = dir.join("square.SVG");
        write(&svg, (10, 10), &Square).unwrap();
        assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
        let png = dir.join("square.Png");
        write(&png, (10, 10), &Square).unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
        let jpg = dir.join("square.jpg");
        assert!(matches!(
            write(&jpg, (10, 10), &Square),
            Err(FigureError::Extension { .. })
        ));
        assert!(!jpg.exists());
        let e = write(&dir.join("broken.svg"), (10, 10), &Broken).unwrap_err();
        assert!(e.to_string().contains("broken.svg"), "{e}");
        assert!(e.to_string().contains("no data to draw"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn prepare_refuses_unwritable_paths_and_leaves_no_trace() {
        let dir = std::env::temp_dir().join(format!("stiffwall-prepare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let missing_dir = dir.join("no/such/dir/a.svg");
        let e = prepare(&missing_dir).unwrap_err();
        assert!(matches!(e, FigureError::Unwritable { .. }), "{e}");
        assert!(e.to_string().contains("no/such/dir/a.svg"), "{e}");
        let is_dir = dir.join("sub.png");
        std::fs::create_dir_all(&is_dir).unwrap();
        assert!(matches!(
            prepare(&is_dir),
            Err(FigureError::Unwritable { .. })
        ));
        let fresh = dir.join("fresh.svg");
        assert_eq!(prepare(&fresh).unwrap(), Format::Svg);
        assert!(!fresh.exists(), "the check must not leave a file behind");
        let old = dir.join("old.png");
        std::fs::write(&old, b"keep").unwrap();
        prepare(&old).unwrap();
        assert_eq!(std::fs::read(&old).unwrap(), b"keep");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
