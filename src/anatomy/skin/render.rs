//! A small software rasteriser for pictures of the skin: orthographic camera, z-buffer,
//! Lambert shading, markers drawn as discs joined by grid lines, written as PNG.

use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::path::Path;

/// Camera and image settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width [px].
    pub width: u32,
    /// Image height [px].
    pub height: u32,
    /// Direction from the subject towards the camera (x anterior, y superior, z right).
    pub toward_camera: Vector3<f64>,
    /// Marker disc radius [px].
    pub marker_radius: f64,
}

impl Default for RenderOptions {
    /// A front view turned 25 degrees towards the subject's right and 10 degrees from above.
    fn default() -> Self {
        RenderOptions {
            width: 600,
            height: 800,
            toward_camera: Vector3::new(0.89, 0.17, 0.42),
            marker_radius: 4.0,
        }
    }
}

/// An RGB picture.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width [px].
    pub width: usize,
    /// Height [px].
    pub height: usize,
    /// Row-major pixels from the top-left corner.
    pub pixels: Vec<[u8; 3]>,
}

impl RgbImage {
    /// Places pictures of equal height side by side.
    pub fn hstack(images: &[RgbImage]) -> Result<RgbImage> {
        let height = images.first().map(|i| i.height).unwrap_or(0);
        if images.is_empty() || images.iter().any(|i| i.height != height) {
            return Err(Error::invalid(
                "picture panels",
                images.len(),
                "one or more panels of equal height",
            ));
        }
        let width = images.iter().map(|i| i.width).sum();
        let mut pixels = Vec::with_capacity(width * height);
        for y in 0..height {
            for i in images {
                pixels.extend_from_slice(&i.pixels[y * i.width..(y + 1) * i.width]);
            }
        }
        Ok(RgbImage {
            width,
            height,
            pixels,
        })
    }

    /// Writes the picture as an 8-bit RGB PNG.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let data: Vec<u8> = self.pixels.iter().flatten().copied().collect();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
        let mut enc = png::Encoder::new(
            std::io::BufWriter::new(file),
            self.width as u32,
            self.height as u32,
        );
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let png_err = |e: png::EncodingError| Error::io(path, std::io::Error::other(e.to_string()));
        let mut writer = enc.write_header().map_err(png_err)?;
        writer.write_image_data(&data).map_err(png_err)?;
        writer.finish().map_err(png_err)
    }
}

/// A shaded picture of a triangle surface with markers (drawn where visible) and lines
/// between pairs of markers (index pairs), written to `path` as an RGB PNG.
pub fn render_png(
    path: &Path,
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    markers: &[Point3<f64>],
    marker_links: &[(usize, usize)],
    options: &RenderOptions,
) -> Result<()> {
    render_rgb(vertices, triangles, markers, marker_links, &[], options)?.write_png(path)
}

/// A shaded picture of a triangle surface with markers, lines between pairs of markers and
/// arrows (segments from a point to another, drawn in green with the end point marked; used
/// for magnified marker displacements). The framing fits the surface.
pub fn render_rgb(
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    markers: &[Point3<f64>],
    marker_links: &[(usize, usize)],
    arrows: &[(Point3<f64>, Point3<f64>)],
    options: &RenderOptions,
) -> Result<RgbImage> {
    let (w, h) = (options.width as usize, options.height as usize);
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        return Err(Error::invalid(
            "image size",
            format!("{w} x {h}"),
            "16..=8192 pixels each",
        ));
    }
    let e = options
        .toward_camera
        .try_normalize(1e-12)
        .ok_or_else(|| Error::invalid("camera direction", "zero", "a non-zero vector"))?;
    let f = -e;
    let right = f
        .cross(&Vector3::y())
        .try_normalize(1e-9)
        .unwrap_or(Vector3::z());
    let up = right.cross(&f);
    let proj = |p: &Point3<f64>| (p.coords.dot(&right), p.coords.dot(&up), p.coords.dot(&e));
    let pts: Vec<(f64, f64, f64)> = vertices.iter().map(proj).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    let scale = 0.9 * (w as f64 / (x1 - x0).max(1e-9)).min(h as f64 / (y1 - y0).max(1e-9));
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let to_px = |p: (f64, f64, f64)| {
        (
            0.5 * w as f64 + (p.0 - cx) * scale,
            0.5 * h as f64 - (p.1 - cy) * scale,
            p.2,
        )
    };
    let spts: Vec<(f64, f64, f64)> = pts.into_iter().map(to_px).collect();

    let mut image = vec![[246u8, 246, 246]; w * h];
    let mut depth = vec![f64::MIN; w * h];
    let light = (e + 0.6 * up + 0.3 * right).normalize();
    for t in triangles {
        let (a, b, c) = (
            &vertices[t[0] as usize],
            &vertices[t[1] as usize],
            &vertices[t[2] as usize],
        );
        let Some(n) = (b - a).cross(&(c - a)).try_normalize(1e-300) else {
            continue;
        };
        if n.dot(&e) <= 0.0 {
            continue;
        }
        let shade = 0.22 + 0.78 * n.dot(&light).max(0.0);
        let colour = [
            (232.0 * shade) as u8,
            (190.0 * shade) as u8,
            (160.0 * shade) as u8,
        ];
        let (p, q, r) = (
            spts[t[0] as usize],
            spts[t[1] as usize],
            spts[t[2] as usize],
        );
        let area = (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0);
        if area.abs() < 1e-12 {
            continue;
        }
        let xa = p.0.min(q.0).min(r.0).floor().max(0.0) as usize;
        let xb = (p.0.max(q.0).max(r.0).ceil() as usize).min(w - 1);
        let ya = p.1.min(q.1).min(r.1).floor().max(0.0) as usize;
        let yb = (p.1.max(q.1).max(r.1).ceil() as usize).min(h - 1);
        for py in ya..=yb {
            for px in xa..=xb {
                let (sx, sy) = (px as f64 + 0.5, py as f64 + 0.5);
                let w0 = ((q.0 - sx) * (r.1 - sy) - (q.1 - sy) * (r.0 - sx)) / area;
                let w1 = ((r.0 - sx) * (p.1 - sy) - (r.1 - sy) * (p.0 - sx)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * p.2 + w1 * q.2 + w2 * r.2;
                let k = py * w + px;
                if z > depth[k] {
                    depth[k] = z;
                    image[k] = colour;
                }
            }
        }
    }
    let mpx: Vec<(f64, f64, f64)> = markers.iter().map(|m| to_px(proj(m))).collect();
    let visible = |p: &(f64, f64, f64)| {
        let (x, y) = (p.0 as isize, p.1 as isize);
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
            return false;
        }
        p.2 >= depth[y as usize * w + x as usize] - 0.004
    };
    for &(i, j) in marker_links {
        let (Some(a), Some(b)) = (mpx.get(i), mpx.get(j)) else {
            continue;
        };
        if !(visible(a) && visible(b)) {
            continue;
        }
        let steps = ((b.0 - a.0).hypot(b.1 - a.1).ceil() as usize).max(1);
        for s in 0..=steps {
            let f = s as f64 / steps as f64;
            let (x, y) = (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f);
            if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
                image[y as usize * w + x as usize] = [40, 60, 150];
            }
        }
    }
    let rad = options.marker_radius;
    for (a, b) in arrows {
        let (pa, pb) = (to_px(proj(a)), to_px(proj(b)));
        if !visible(&pa) {
            continue;
        }
        let steps = ((pb.0 - pa.0).hypot(pb.1 - pa.1).ceil() as usize).max(1);
        for s in 0..=steps {
            let f = s as f64 / steps as f64;
            let (x, y) = (pa.0 + (pb.0 - pa.0) * f, pa.1 + (pb.1 - pa.1) * f);
            for (ox, oy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let (x, y) = (x + ox - 0.5, y + oy - 0.5);
                if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
                    image[y as usize * w + x as usize] = [20, 150, 60];
                }
            }
        }
        let r = 2isize;
        for dy in -r..=r {
            for dx in -r..=r {
                let (x, y) = (pb.0 as isize + dx, pb.1 as isize + dy);
                if dx * dx + dy * dy <= r * r
                    && x >= 0
                    && y >= 0
                    && (x as usize) < w
                    && (y as usize) < h
                {
                    image[y as usize * w + x as usize] = [20, 150, 60];
                }
            }
        }
    }
    for p in mpx.iter().filter(|p| visible(p)) {
        let r = rad.ceil() as isize;
        for dy in -r..=r {
            for dx in -r..=r {
                let (x, y) = (p.0 as isize + dx, p.1 as isize + dy);
                if (dx * dx + dy * dy) as f64 <= rad * rad
                    && x >= 0
                    && y >= 0
                    && (x as usize) < w
                    && (y as usize) < h
                {
                    image[y as usize * w + x as usize] = [200, 20, 30];
                }
            }
        }
    }
    Ok(RgbImage {
        width: w,
        height: h,
        pixels: image,
    })
}
