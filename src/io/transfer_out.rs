//! Transfer functions (colour and opacity over a value range) as a ParaView preset (`.json`)
//! or as CSV (`.csv`).
//!
//! The ParaView preset is what *Color Map Editor → Choose Preset → Import* (or
//! `paraview.simple.ImportPresets`) reads: a JSON array holding one object with `Name`,
//! `ColorSpace` (`RGB`: the colours are interpolated as given), `NanColor`, `RGBPoints`
//! (`x, r, g, b` flattened) and `Points` (the opacity function, `x, opacity, midpoint,
//! sharpness` flattened, midpoint 0.5 and sharpness 0: linear). The abscissae are data values;
//! keep the preset's range when applying it ("Use preset range") or rescale it to the same data
//! range.
//!
//! The CSV has the header `value,r,g,b,opacity` and one row per abscissa of either function
//! (sorted), the other function interpolated linearly there.

use std::io::{self, Write};
use std::path::Path;

use super::atomic::{write_atomically, WriteError};

pub use super::formats::TransferFormat;

/// A transfer function to write: control points sorted by strictly increasing value, both
/// functions over the same range.
#[derive(Clone, Copy, Debug)]
pub struct TransferTable<'a> {
    /// Preset name (shown in ParaView's preset list).
    pub name: &'a str,
    /// Colour control points `[value, r, g, b]`, components in `[0, 1]`.
    pub colors: &'a [[f64; 4]],
    /// Opacity control points `[value, opacity]`.
    pub opacity: &'a [[f64; 2]],
}

/// Writes `table` to `path` in `format`, atomically.
///
/// # Errors
/// [`WriteError`] (one line naming `path`); nothing is left at `path` on failure.
pub fn write_transfer(
    path: &Path,
    format: TransferFormat,
    table: &TransferTable,
) -> Result<(), WriteError> {
    write_atomically(path, |w| match format {
        TransferFormat::ParaView => write_paraview(w, table),
        TransferFormat::Csv => write_csv(w, table),
    })
}

fn write_paraview(w: &mut dyn Write, t: &TransferTable) -> io::Result<()> {
    let rgb: Vec<f64> = t.colors.iter().flatten().copied().collect();
    let points: Vec<f64> = t
        .opacity
        .iter()
        .flat_map(|&[x, a]| [x, a, 0.5, 0.0])
        .collect();
    let preset = serde_json::json!([{
        "Name": t.name,
        "Creator": "tptd",
        "ColorSpace": "RGB",
        "NanColor": [1.0, 1.0, 0.0],
        "RGBPoints": rgb,
        "Points": points,
    }]);
    serde_json::to_writer_pretty(&mut *w, &preset).map_err(io::Error::other)?;
    writeln!(w)
}

fn write_csv(w: &mut dyn Write, t: &TransferTable) -> io::Result<()> {
    writeln!(w, "value,r,g,b,opacity")?;
    let mut xs: Vec<f64> = t
        .colors
        .iter()
        .map(|p| p[0])
        .chain(t.opacity.iter().map(|p| p[0]))
        .collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    for x in xs {
        let [r, g, b] = interpolate(t.colors, x, |p| [p[1], p[2], p[3]]);
        let [a] = interpolate(t.opacity, x, |p| [p[1]]);
        writeln!(w, "{x},{r},{g},{b},{a}")?;
    }
    Ok(())
}

/// The value of the piecewise-linear function with control points `pts` (first entry the
/// abscissa, `get` the ordinates) at `x`, constant beyond the ends.
fn interpolate<const N: usize, P: AsRef<[f64]>>(
    pts: &[P],
    x: f64,
    get: impl Fn(&P) -> [f64; N],
) -> [f64; N] {
    let at = |p: &P| p.as_ref()[0];
    let Some(i) = pts.iter().position(|p| at(p) >= x) else {
        return pts.last().map_or([0.0; N], &get);
    };
    if i == 0 || at(&pts[i]) == x {
        return get(&pts[i]);
    }
    let (a, b) = (&pts[i - 1], &pts[i]);
    let t = (x - at(a)) / (at(b) - at(a));
    let (ga, gb) = (get(a), get(b));
    std::array::from_fn(|k| ga[k] + t * (gb[k] - ga[k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLORS: [[f64; 4]; 3] = [
        [0.0, 0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0, 0.0],
        [3.0, 0.0, 1.0, 0.0],
    ];
    const OPACITY: [[f64; 2]; 3] = [[0.0, 0.0], [2.0, 1.0], [3.0, 0.5]];

    fn table() -> TransferTable<'static> {
        TransferTable {
            name: "test",
            colors: &COLORS,
            opacity: &OPACITY,
        }
    }

    #[test]
    fn csv_rows_at_every_abscissa_with_the_other_function_interpolated() {
        let mut out = Vec::new();
        write_csv(&mut out, &table()).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(
            text,
            "value,r,g,b,opacity\n0,0,0,1,0\n1,1,0,0,0.5\n2,0.5,0.5,0,1\n3,0,1,0,0.5\n"
        );
    }

    #[test]
    fn paraview_preset_layout() {
        let mut out = Vec::new();
        write_paraview(&mut out, &table()).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
        let p = &v.as_array().unwrap()[0];
        assert_eq!(p["Name"], "test");
        assert_eq!(p["ColorSpace"], "RGB");
        assert_eq!(
            p["RGBPoints"],
            serde_json::json!([0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 3.0, 0.0, 1.0, 0.0])
        );
        assert_eq!(
            p["Points"],
            serde_json::json!([0.0, 0.0, 0.5, 0.0, 2.0, 1.0, 0.5, 0.0, 3.0, 0.5, 0.5, 0.0])
        );
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            TransferFormat::from_path(Path::new("a/b.JSON")),
            Some(TransferFormat::ParaView)
        );
        assert_eq!(
            TransferFormat::from_path(Path::new("t.csv")),
            Some(TransferFormat::Csv)
        );
        assert_eq!(TransferFormat::from_path(Path::new("t.xml")), None);
        assert_eq!(TransferFormat::from_path(Path::new("t")), None);
    }
}
