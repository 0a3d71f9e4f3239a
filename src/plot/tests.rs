//! Tests of the figures: PNG, SVG and in-memory rendering, validation errors, helpers.

use super::field::*;
use super::heatmap::*;
use super::line::*;
use super::stacked::*;
use super::*;
use crate::io::tests::temp_dir;

fn axes(title: &str, xs: Scale, ys: Scale) -> Axes {
    Axes {
        title: title.to_string(),
        x_label: "time (µs)".to_string(),
        y_label: "u_y (nm)".to_string(),
        x_scale: xs,
        y_scale: ys,
    }
}

fn wave(label: &str, f: f64) -> Series {
    let x: Vec<f64> = (0..400).map(|i| f64::from(i) * 0.05).collect();
    let y = x
        .iter()
        .map(|t| (f * t).sin() * (-(t - 10.0) * (t - 10.0) / 8.0).exp())
        .collect();
    Series {
        label: label.to_string(),
        x,
        y,
    }
}

/// A small rectangular mesh with a field varying in x and y.
fn mesh() -> (Vec<[f64; 2]>, Vec<[usize; 3]>, Vec<f64>) {
    let (nx, ny) = (20, 6);
    let mut nodes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([f64::from(i) * 2.0, f64::from(j)]);
        }
    }
    let id = |i: usize, j: usize| j * (nx as usize + 1) + i;
    let mut tris = Vec::new();
    for j in 0..ny as usize {
        for i in 0..nx as usize {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let vals = nodes.iter().map(|p| (p[0] * 0.3).sin() * p[1]).collect();
    (nodes, tris, vals)
}

/// Renders `fig` into an RGB buffer; returns (buffer, width, height).
fn to_buffer(fig: &impl Figure) -> (Vec<u8>, u32, u32) {
    ensure_font(Path::new("buffer")).expect("font");
    let (w, h) = fig.size();
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        paint(root, fig).expect("draw into buffer");
    }
    (buf, w, h)
}

/// Number of dark pixels in rows `rows` of an RGB buffer of width `w`.
fn dark_pixels(buf: &[u8], w: u32, rows: Range<u32>) -> usize {
    let row_bytes = (w * 3) as usize;
    buf[rows.start as usize * row_bytes..rows.end as usize * row_bytes]
        .chunks(3)
        .filter(|p| p.iter().all(|&c| c < 100))
        .count()
}

/// Asserts the file is a PNG of the given size (IHDR width and height).
fn assert_png(path: &Path, (w, h): (u32, u32)) {
    let bytes = std::fs::read(path).expect("read png");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |o: usize| u32::from_be_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    assert_eq!((be(16), be(20)), (w, h));
}

/// Asserts the SVG has text elements and contains `title`.
fn assert_svg(path: &Path, title: &str) {
    let text = std::fs::read_to_string(path).expect("read svg");
    assert!(text.contains("<text"), "no text in {}", path.display());
    assert!(text.contains(title), "title missing in {}", path.display());
}

/// Checks buffer rendering (title pixels) and PNG/SVG files for a figure.
fn check_figure(fig: &impl Figure, title: &str, write: impl Fn(&Path) -> Result<(), PlotError>) {
    let (buf, w, h) = to_buffer(fig);
    assert!(dark_pixels(&buf, w, 0..45) > 100, "title not rendered");
    assert!(
        dark_pixels(&buf, w, 45..h) > 1000,
        "no axes or labels rendered"
    );
    let dir = temp_dir("fig");
    let png = dir.join("a/fig.png");
    write(&png).expect("png");
    assert_png(&png, fig.size());
    let svg = dir.join("fig.svg");
    write(&svg).expect("svg");
    assert_svg(&svg, title);
    let mut names: Vec<_> = std::fs::read_dir(&*dir)
        .expect("dir")
        .map(|e| e.expect("e").file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["a", "fig.svg"], "temporary files left behind");
}

#[test]
fn line_plot_png_svg_buffer() {
    let a = axes("Focusing at receiver 3", Scale::Linear, Scale::Linear);
    let s = [wave("linear", 3.0), wave("cracked", 3.3)];
    let fig = LineFig {
        axes: &a,
        series: &s,
        markers: false,
    };
    check_figure(&fig, &a.title, |p| line_plot(p, &a, &s, false));
}

#[test]
fn log_line_plot_with_markers() {
    let a = axes("Work-precision", Scale::Log10, Scale::Log10);
    let s = [Series {
        label: "central difference".into(),
        x: vec![0.1, 0.4, 2.0, 9.0],
        y: vec![1e-2, 3e-3, 4e-4, 1e-5],
    }];
    let fig = LineFig {
        axes: &a,
        series: &s,
        markers: true,
    };
    check_figure(&fig, &a.title, |p| line_plot(p, &a, &s, true));
}

#[test]
fn stacked_plot_png_svg_buffer() {
    let panels: Vec<Panel> = (1..=3)
        .map(|r| Panel {
            title: format!("Receiver {r}"),
            series: vec![wave("sim", f64::from(r)), wave("pred", f64::from(r) + 0.2)],
        })
        .collect();
    let fig = StackedFig {
        title: "TR-NEWS focusing",
        x_label: "t (µs)",
        y_label: "u (nm)",
        panels: &panels,
    };
    assert_eq!(fig.size(), (1000, 50 + 3 * 220 + 60));
    check_figure(&fig, fig.title, |p| {
        stacked_plot(p, fig.title, "t (µs)", "u (nm)", &panels)
    });
}

#[test]
fn heatmap_png_svg_buffer() {
    let a = axes(
        "Departure from linear prediction",
        Scale::Linear,
        Scale::Log10,
    );
    let x: Vec<f64> = (0..30).map(f64::from).collect();
    let y: Vec<f64> = (0..12).map(|k| 10f64.powf(f64::from(k) / 4.0)).collect();
    let v: Vec<Vec<f64>> = y
        .iter()
        .map(|yy| x.iter().map(|xx| (xx * 0.2).sin() * yy.ln()).collect())
        .collect();
    let fig = HeatFig::new(Path::new("t.png"), &a, &x, &y, &v, "error (dB)").expect("valid");
    check_figure(&fig, &a.title, |p| heatmap(p, &a, &x, &y, &v, "error (dB)"));
}

#[test]
fn field_plot_png_svg_buffer() {
    let a = axes("u_y snapshot", Scale::Linear, Scale::Linear);
    let (n, t, v) = mesh();
    let ov = [
        Overlay {
            points: vec![(0.0, 3.0), (40.0, 3.0)],
            color: (128, 128, 128),
            width: 1,
        },
        Overlay {
            points: vec![(15.0, 2.0), (25.0, 2.0)],
            color: (0, 0, 0),
            width: 4,
        },
    ];
    let fig = FieldFig::new(Path::new("t.png"), &a, &n, &t, &v, &ov, "u_y (nm)").expect("valid");
    check_figure(&fig, &a.title, |p| {
        field_plot(p, &a, &n, &t, &v, &ov, "u_y (nm)")
    });
    let (buf, w, h) = to_buffer(&fig);
    let reds = buf.chunks(3).filter(|p| p[0] > 150 && p[2] < 110).count();
    let blues = buf.chunks(3).filter(|p| p[2] > 150 && p[0] < 110).count();
    assert!(
        reds > 1000 && blues > 1000,
        "diverging colours missing ({reds}, {blues}) in {w}x{h}"
    );
}

#[test]
fn raster_interpolates_linear_field_exactly() {
    let a = axes("", Scale::Linear, Scale::Linear);
    let (n, t, _) = mesh();
    let v: Vec<f64> = n.iter().map(|p| 2.0 * p[0] - p[1]).collect();
    let fig = FieldFig::new(Path::new("t.png"), &a, &n, &t, &v, &[], "").expect("valid");
    let (xr, yr) = (0.0..40.0, 0.0..6.0);
    let r = Raster::sample(&fig, (&xr, &yr), (80, 12));
    assert!(
        r.cells.iter().all(Option::is_some),
        "pixels missed inside the mesh"
    );
    let (i, j) = (13, 5);
    let (x, y) = ((i as f64 + 0.5) * 0.5, 6.0 - (j as f64 + 0.5) * 0.5);
    let got = r.cells[j * 80 + i].expect("inside");
    assert!((got - (2.0 * x - y)).abs() < 1e-9, "{got}");
}

#[test]
fn log_axis_with_zero_errors() {
    let a = axes("log", Scale::Linear, Scale::Log10);
    let s = [Series {
        label: "decay".into(),
        x: vec![1.0, 2.0],
        y: vec![1.0, 0.0],
    }];
    let dir = temp_dir("log0");
    let err = line_plot(&dir.join("f.png"), &a, &s, false).expect_err("must fail");
    assert!(
        matches!(
            err,
            PlotError::NonPositiveLog {
                axis: "y",
                index: 1,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string().contains("decay") && err.to_string().contains("f.png"),
        "{err}"
    );
    assert!(std::fs::read_dir(&*dir).expect("dir").next().is_none());
}

#[test]
fn nan_and_empty_error() {
    let a = axes("nan", Scale::Linear, Scale::Linear);
    let dir = temp_dir("nan");
    let s = [Series {
        label: "bad".into(),
        x: vec![1.0, 2.0],
        y: vec![f64::NAN, 0.0],
    }];
    let err = line_plot(&dir.join("f.svg"), &a, &s, false).expect_err("nan");
    assert!(
        matches!(err, PlotError::NonFinite { .. }) && err.to_string().contains("bad"),
        "{err}"
    );
    let e = [Series {
        label: "none".into(),
        x: vec![],
        y: vec![],
    }];
    assert!(matches!(
        line_plot(&dir.join("f.png"), &a, &e, false),
        Err(PlotError::Empty { .. })
    ));
    assert!(matches!(
        line_plot(&dir.join("f.png"), &a, &[], false),
        Err(PlotError::Empty { .. })
    ));
    assert!(matches!(
        stacked_plot(&dir.join("f.png"), "t", "x", "y", &[]),
        Err(PlotError::Empty { .. })
    ));
    let hv = vec![vec![1.0, f64::INFINITY]];
    let err = heatmap(&dir.join("h.png"), &a, &[0.0, 1.0], &[0.0], &hv, "c").expect_err("inf");
    assert!(err.to_string().contains("heatmap row 0"), "{err}");
}

#[test]
fn unknown_extension_errors() {
    let a = axes("ext", Scale::Linear, Scale::Linear);
    let dir = temp_dir("ext");
    let err = line_plot(&dir.join("fig.jpg"), &a, &[wave("w", 1.0)], false).expect_err("jpg");
    assert!(
        matches!(&err, PlotError::UnknownExtension { ext, .. } if ext == "jpg"),
        "{err}"
    );
    assert!(err.to_string().contains("fig.jpg"), "{err}");
    assert!(std::fs::read_dir(&*dir).expect("dir").next().is_none());
}

#[test]
fn bad_mesh_and_grid_error() {
    let a = axes("mesh", Scale::Linear, Scale::Linear);
    let (n, mut t, v) = mesh();
    t.push([0, 1, n.len()]);
    let err =
        field_plot(Path::new("/nonexistent/x.png"), &a, &n, &t, &v, &[], "").expect_err("index");
    assert!(err.to_string().contains("triangle"), "{err}");
    let err = heatmap(
        Path::new("h.png"),
        &a,
        &[1.0, 0.5],
        &[0.0],
        &[vec![1.0, 2.0]],
        "",
    )
    .expect_err("order");
    assert!(err.to_string().contains("strictly increasing"), "{err}");
}

#[test]
fn helpers_behave() {
    assert_eq!(tick_label(&0.30000000000000004), "0.3");
    assert_eq!(tick_label(&2.5e-6), "2.5e-6");
    assert_eq!(tick_label(&0.0), "0");
    let r = log_range(2.0, 3.0);
    assert!(
        (r.start - 1.0).abs() < 1e-5 && (r.end - 10.0).abs() < 1e-4,
        "{r:?}"
    );
    assert_eq!(
        cell_edges(&[0.0, 1.0, 3.0], Scale::Linear),
        vec![-0.5, 0.5, 2.0, 4.0]
    );
    let e = cell_edges(&[1.0, 100.0], Scale::Log10);
    assert!(
        (e[0] - 0.1).abs() < 1e-12 && (e[1] - 10.0).abs() < 1e-9 && (e[2] - 1000.0).abs() < 1e-6
    );
    assert_eq!(colormap(&DIVERGING, 0.5), RGBColor(247, 247, 247));
}
