//! Light propagation volumes on the CPU: the reference the GPU passes are tested against.
//!
//! Two schemes live here (see `docs/lpv.md`):
//!
//! - **Kaplanyan & Dachsbacher (2010)**, lightlab's `lpv`: virtual point lights (VPLs) from a
//!   reflective shadow map are *scattered* into the cell that holds the VPL shifted half a cell
//!   along its normal, as the 2-band SH of their radiant intensity Φ/π·max(0, n·ω); light moves
//!   by gathering from the 6 face neighbours onto the 5 faces of the receiving cell (exact face
//!   solid angles), each face's flux re-emitted as a clamped-cosine lobe around the face normal;
//!   each iteration holds only newly arrived light and is summed into an accumulation volume;
//!   a geometry volume (half a cell offset) of blocking potentials attenuates light across faces,
//!   skipped on the first iteration.
//! - **WPI 2011** (Dickson, Sandbrook & Oliver), lightlab's `lpv-faithful`: the report's
//!   18-neighbour additive gather (`out = in + Σ f·w·max(0, I_n(d))·Y(d) / 18`, f = 0.65, edge
//!   neighbours ×0.5, clamp-to-edge borders). It is not energy conserving; its regression values
//!   (§5.5 of the extraction) are unit tests here.
//!
//! Units: a cell's SH holds radiant intensity I(ω) [W/sr] leaving the cell; radiance near the cell
//! is I/s² (s = cell size), so irradiance on a surface of normal n is the cosine convolution of
//! I(−ω)/s² (Ramamoorthi–Hanrahan factors π and 2π/3).
//!
//! SH order and signs are lightlab's (`crate::sh`): (Y₀₀, Y₁₋₁ ∝ y, Y₁₀ ∝ z, Y₁₁ ∝ x), all
//! positive. The WPI shaders order band 1 as (x, y, z); Crytek's as (−y, z, −x); both are
//! permutations/sign flips of this one.
//!
//! No crate implements LPVs; this module is our own, written from the papers.

use glam::{IVec3, Vec3};

/// Y₀₀ = 1/(2√π).
pub const Y00: f32 = 0.282_094_8;
/// The band-1 constant √(3/4π).
pub const C1: f32 = 0.488_602_5;
/// Solid angle of the far face of the receiving cell seen from the source cell's centre:
/// 4·asin(1/(1 + 4·1.5²)) (checked against the exact rectangle formula in the unit test).
pub const SOLID_ANGLE_FAR: f32 = 0.400_669_7;
/// Solid angle of one side face of the receiving cell seen from the source cell's centre:
/// (2π/3 − far)/4 = 0.4234313544. Erratum: the value 0.4234413544 quoted in many LPV
/// implementations (and in our extraction) has a transposed digit; with it far + 4·side exceeds
/// the shared face's 2π/3 by 4·10⁻⁵.
pub const SOLID_ANGLE_SIDE: f32 = 0.423_431_35;

/// Two-band SH coefficients in lightlab's order.
pub type Sh4 = [f32; 4];
/// One cell: SH per colour channel (r, g, b).
pub type Cell = [Sh4; 3];

/// The SH basis evaluated in direction `d` (unit): the projection of a delta in `d`.
pub fn basis(d: Vec3) -> Sh4 {
    [Y00, C1 * d.y, C1 * d.z, C1 * d.x]
}

/// Projection of the clamped cosine max(0, n·ω): (√π/2, √(π/3)·n).
pub fn cosine_lobe(n: Vec3) -> Sh4 {
    const A0: f32 = 0.886_226_9; // √π/2
    const A1: f32 = 1.023_326_7; // √(π/3)
    [A0, A1 * n.y, A1 * n.z, A1 * n.x]
}

pub fn dot(a: &Sh4, b: &Sh4) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}

/// Evaluate SH `c` in direction `d`.
pub fn eval(c: &Sh4, d: Vec3) -> f32 {
    dot(c, &basis(d))
}

fn scaled(c: &Sh4, s: f32) -> Sh4 {
    [c[0] * s, c[1] * s, c[2] * s, c[3] * s]
}

fn add_to(acc: &mut Sh4, c: &Sh4, s: f32) {
    for i in 0..4 {
        acc[i] += c[i] * s;
    }
}

/// A cubic grid of n³ cubic cells: cell (i, j, k) spans origin + [i, i+1)·cell, etc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub n: u32,
    pub origin: Vec3,
    pub cell: f32,
}

impl Grid {
    /// The grid of `n`³ cells whose cube holds the box [lo, hi] centred, with `margin` cells of
    /// space on every side of the box's largest extent.
    pub fn around(lo: Vec3, hi: Vec3, n: u32, margin: f32) -> Grid {
        let n = n.max(1);
        let extent = (hi - lo).max_element().max(1e-6);
        let cell = extent / (n as f32 - 2.0 * margin).max(1.0);
        let centre = 0.5 * (lo + hi);
        Grid {
            n,
            origin: centre - Vec3::splat(0.5 * cell * n as f32),
            cell,
        }
    }

    pub fn len(&self) -> usize {
        (self.n as usize).pow(3)
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    pub fn index(&self, c: IVec3) -> usize {
        let n = self.n as usize;
        (c.z as usize * n + c.y as usize) * n + c.x as usize
    }

    pub fn contains(&self, c: IVec3) -> bool {
        let n = self.n as i32;
        c.cmpge(IVec3::ZERO).all() && c.cmplt(IVec3::splat(n)).all()
    }

    /// The cell holding `p`, if inside the grid.
    pub fn cell_of(&self, p: Vec3) -> Option<IVec3> {
        let c = ((p - self.origin) / self.cell).floor().as_ivec3();
        self.contains(c).then_some(c)
    }

    pub fn centre(&self, c: IVec3) -> Vec3 {
        self.origin + (c.as_vec3() + 0.5) * self.cell
    }

    pub fn cells(&self) -> impl Iterator<Item = IVec3> + '_ {
        let n = self.n as i32;
        (0..n).flat_map(move |z| (0..n).flat_map(move |y| (0..n).map(move |x| IVec3::new(x, y, z))))
    }
}

/// A virtual point light: a surfel of the reflective shadow map.
#[derive(Clone, Copy, Debug)]
pub struct Vpl {
    pub position: Vec3,
    pub normal: Vec3,
    /// Reflected flux Φ [W] per colour channel.
    pub flux: Vec3,
}

/// A surfel that blocks light: position, unit normal, area [m²] and diffuse albedo (what it
/// reflects of the light it blocks, with [`Bounces::Multiple`]).
#[derive(Clone, Copy, Debug)]
pub struct Surfel {
    pub position: Vec3,
    pub normal: Vec3,
    pub area: f32,
    pub albedo: Vec3,
}

/// A light propagation volume: intensity SH per cell and colour.
#[derive(Clone, Debug)]
pub struct Volume {
    pub grid: Grid,
    pub cells: Vec<Cell>,
}

impl Volume {
    pub fn new(grid: Grid) -> Volume {
        Volume {
            grid,
            cells: vec![[[0.0; 4]; 3]; grid.len()],
        }
    }

    pub fn at(&self, c: IVec3) -> &Cell {
        &self.cells[self.grid.index(c)]
    }

    /// Total flux Σ ∫I dω = Σ √(4π)·c₀ per colour (the band-1 terms integrate to zero).
    pub fn total_flux(&self) -> Vec3 {
        let k = 4.0 * std::f32::consts::PI * Y00;
        let mut t = [0.0f64; 3];
        for c in &self.cells {
            for (ch, sh) in c.iter().enumerate() {
                t[ch] += (sh[0] * k) as f64;
            }
        }
        Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32)
    }

    /// Add `other` (same grid) into this volume.
    pub fn accumulate(&mut self, other: &Volume) {
        for (a, b) in self.cells.iter_mut().zip(&other.cells) {
            for ch in 0..3 {
                add_to(&mut a[ch], &b[ch], 1.0);
            }
        }
    }

    /// Trilinear interpolation of the cell SH at `p` (cell centres are the samples; clamped at
    /// the border).
    pub fn sample(&self, p: Vec3) -> Cell {
        let g = &self.grid;
        let f = (p - g.origin) / g.cell - 0.5;
        let max = (g.n - 1) as f32;
        let f = f.clamp(Vec3::ZERO, Vec3::splat(max));
        let base = f.floor().as_ivec3().min(IVec3::splat(g.n as i32 - 1));
        let t = f - base.as_vec3();
        let mut out = [[0.0; 4]; 3];
        for corner in 0..8 {
            let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let c = (base + o).min(IVec3::splat(g.n as i32 - 1));
            let w = (if o.x == 1 { t.x } else { 1.0 - t.x })
                * (if o.y == 1 { t.y } else { 1.0 - t.y })
                * (if o.z == 1 { t.z } else { 1.0 - t.z });
            if w == 0.0 {
                continue;
            }
            let cell = self.at(c);
            for ch in 0..3 {
                add_to(&mut out[ch], &cell[ch], w);
            }
        }
        out
    }

    /// Irradiance E [W/m²] at `p` on a surface of normal `n`, as lightlab's `lpv` shades: the
    /// volume is read half a cell along n (against bleeding through thin walls), incident radiance
    /// is I(−ω)/s², convolved with the clamped cosine; negative results clamp to 0.
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        let s = self.grid.cell;
        let sh = self.sample(p + 0.5 * s * n);
        let mut e = [0.0f32; 3];
        for ch in 0..3 {
            e[ch] = irradiance_of(&sh[ch], n, s);
        }
        Vec3::from_array(e)
    }

    /// [`Volume::irradiance`] with damping against self-illumination: per colour, the smaller of
    /// the irradiance read half a cell along n and the one read `cells` further out.
    ///
    /// Kaplanyan & Dachsbacher damp a lookup by the intensity's directional derivative along the
    /// normal; this is that test as a finite difference. Light arriving from elsewhere changes
    /// slowly along n, while light the surface injected itself (and the 2-band lobes cannot keep
    /// away from it once it has spread sideways) is strongest at the surface and falls off
    /// within a few cells: where the irradiance grows towards the surface, the growth is
    /// dropped. `cells` = 0 is the plain lookup.
    pub fn irradiance_damped(&self, p: Vec3, n: Vec3, cells: f32) -> Vec3 {
        let e = self.irradiance(p, n);
        if cells <= 0.0 {
            return e;
        }
        e.min(self.irradiance(p + cells * self.grid.cell * n, n))
    }
}

/// Irradiance on normal `n` from one channel's intensity SH in a cell of size `s`:
/// (π·c₀·Y₀₀ + 2π/3·c₁·Y₁(−n)) / s², clamped at zero.
pub fn irradiance_of(c: &Sh4, n: Vec3, s: f32) -> f32 {
    use std::f32::consts::PI;
    let y = basis(-n);
    let e = PI * c[0] * y[0] + 2.0 * PI / 3.0 * (c[1] * y[1] + c[2] * y[2] + c[3] * y[3]);
    (e / (s * s)).max(0.0)
}

/// Cascaded volumes (Kaplanyan & Dachsbacher 2010): `count` grids of `scene.n` cells, the last
/// one `scene` itself (fitted around the scene, fixed), each finer one with half the cell size
/// of the next, centred a quarter of its width ahead of `eye` along `forward` and, with `snap`,
/// moved only in whole cells of its own size, so that a camera moving by less than a cell
/// leaves every grid (and the image's indirect light) unchanged. Finest first.
pub fn cascade_grids(scene: Grid, count: u32, eye: Vec3, forward: Vec3, snap: bool) -> Vec<Grid> {
    let count = count.max(1);
    let n = scene.n;
    let mut grids = Vec::with_capacity(count as usize);
    for c in 0..count - 1 {
        let cell = scene.cell / (1u32 << (count - 1 - c)) as f32;
        let centre = eye + forward.normalize_or_zero() * (0.25 * n as f32 * cell);
        let corner = centre / cell - Vec3::splat(0.5 * n as f32);
        let corner = if snap { corner.round() } else { corner };
        grids.push(Grid {
            n,
            origin: corner * cell,
            cell,
        });
    }
    grids.push(scene);
    grids
}

/// Where a lookup at `p` reads cascaded volumes: the finest grid holding `p` at least `border`
/// cells inside, blended over the next `band` cells towards its edge with the next coarser
/// one. Returns (cascade, weight of that cascade; the rest goes to cascade + 1). The last
/// grid is used wherever no finer one holds `p`.
pub fn cascade_weight(grids: &[Grid], p: Vec3, border: f32, band: f32) -> (usize, f32) {
    for (c, g) in grids.iter().enumerate().take(grids.len().saturating_sub(1)) {
        let f = (p - g.origin) / g.cell;
        let d = f.min(Vec3::splat(g.n as f32) - f).min_element();
        if d > border {
            return (c, ((d - border) / band.max(1e-6)).min(1.0));
        }
    }
    (grids.len().saturating_sub(1), 1.0)
}

/// Scatter VPLs into a volume (Kaplanyan): each adds Φ/π·cosine_lobe(n) to the cell holding
/// its position moved half a cell along n; VPLs outside the grid are dropped.
pub fn inject(grid: Grid, vpls: &[Vpl]) -> Volume {
    let mut v = Volume::new(grid);
    for vpl in vpls {
        let Some(c) = grid.cell_of(vpl.position + 0.5 * grid.cell * vpl.normal) else {
            continue;
        };
        let lobe = scaled(&cosine_lobe(vpl.normal), 1.0 / std::f32::consts::PI);
        let cell = &mut v.cells[grid.index(c)];
        for (ch, sh) in cell.iter_mut().enumerate() {
            add_to(sh, &lobe, vpl.flux[ch]);
        }
    }
    v
}

/// Normalisation of a blocker's lobe (see [`Occlusion::inject`]).
pub const BLOCKER_SCALE: f32 = 4.0 / 3.0;

/// The geometry volume: blocking potential SH per cell of a grid offset by half a cell, its
/// (n+1)³ cell centres at the corners of the light volume's cells, and the surfaces' albedo
/// there (Σ albedo·A/s² in xyz, Σ A/s² in w).
#[derive(Clone, Debug)]
pub struct Occlusion {
    pub grid: Grid,
    pub cells: Vec<Sh4>,
    pub albedo: Vec<[f32; 4]>,
}

impl Occlusion {
    /// Blocking potential of surfels (Kaplanyan): each adds (A/s²)·⟨n|ω⟩₊ to the geometry cell
    /// nearest to it. The 2-band projection of the clamped cosine peaks at 0.75, so the lobe is
    /// scaled by 4/3: a surface covering a whole face blocks it fully at normal incidence.
    pub fn inject(light: Grid, surfels: &[Surfel]) -> Occlusion {
        let grid = Grid {
            n: light.n + 1,
            origin: light.origin - Vec3::splat(0.5 * light.cell),
            cell: light.cell,
        };
        let mut cells = vec![[0.0; 4]; grid.len()];
        let mut albedo = vec![[0.0; 4]; grid.len()];
        let inv = 1.0 / (light.cell * light.cell);
        for s in surfels {
            let Some(c) = grid.cell_of(s.position) else {
                continue;
            };
            let i = grid.index(c);
            add_to(
                &mut cells[i],
                &cosine_lobe(s.normal),
                BLOCKER_SCALE * s.area * inv,
            );
            add_to(
                &mut albedo[i],
                &s.albedo.extend(1.0).to_array(),
                s.area * inv,
            );
        }
        Occlusion {
            grid,
            cells,
            albedo,
        }
    }

    /// The geometry cells at the four corners of the face between light cell `c` and its
    /// neighbour `c + axis`: light cell c's corner (i, j, k) is the geometry cell (i, j, k), so
    /// the face towards +axis has corners with that axis at c+1 (c for negative axes).
    fn face_corners(&self, c: IVec3, axis: IVec3) -> [usize; 4] {
        let along = c + axis.max(IVec3::ZERO);
        let (u, v) = perpendicular(axis);
        [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(du, dv)| self.grid.index(along + u * du + v * dv))
    }

    /// Transmittance of light travelling along `dir` through the face between light cell `c`
    /// and its neighbour `c + axis`: 1 − max(B(−dir), B(dir)), B summed over the face's four
    /// corners and divided by four.
    ///
    /// Surfaces block from both sides. Kaplanyan & Dachsbacher's blocker is the clamped cosine
    /// of the surfel's normal, B(−dir), which stops light arriving on a surface's front and
    /// lets through light arriving on its back. A wall that only the sun saw from outside then
    /// let the room's light out, and a wall that only the camera saw from inside let the sky's
    /// light in. Reading the blocker from both sides closes walls either way (its effect on
    /// the demo's scenes: docs/lpv.md, *Measured*).
    pub fn transmittance(&self, c: IVec3, axis: IVec3, dir: Vec3) -> f32 {
        let (front, back) =
            self.face_corners(c, axis)
                .iter()
                .fold((0.0f32, 0.0f32), |(f, b), &g| {
                    (
                        f + eval(&self.cells[g], -dir),
                        b + eval(&self.cells[g], dir),
                    )
                });
        1.0 - (0.25 * front.max(back)).clamp(0.0, 1.0)
    }

    /// The mean albedo of the surfaces at the face between light cell `c` and `c + axis`
    /// (area-weighted over its four corners; 0 where there are none).
    pub fn face_albedo(&self, c: IVec3, axis: IVec3) -> Vec3 {
        let sum = self
            .face_corners(c, axis)
            .iter()
            .fold(glam::Vec4::ZERO, |a, &g| {
                a + glam::Vec4::from(self.albedo[g])
            });
        if sum.w > 0.0 {
            sum.truncate() / sum.w
        } else {
            Vec3::ZERO
        }
    }
}

/// The two positive unit axes perpendicular to an axis direction.
fn perpendicular(axis: IVec3) -> (IVec3, IVec3) {
    if axis.x != 0 {
        (IVec3::Y, IVec3::Z)
    } else if axis.y != 0 {
        (IVec3::X, IVec3::Z)
    } else {
        (IVec3::X, IVec3::Y)
    }
}

/// The six axis directions.
pub const AXES: [IVec3; 6] = [
    IVec3::new(1, 0, 0),
    IVec3::new(-1, 0, 0),
    IVec3::new(0, 1, 0),
    IVec3::new(0, -1, 0),
    IVec3::new(0, 0, 1),
    IVec3::new(0, 0, -1),
];

/// Which way the light that crosses a side face of the receiving cell is re-emitted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reemit {
    /// Kaplanyan & Dachsbacher: a cosine lobe around the face's normal (the light is turned by
    /// 90°: most of the transport's diffusion, see `two_band_transport_is_diffusive`).
    FaceNormal,
    /// A cosine lobe around the direction the light travelled, from the source cell's centre
    /// to the face's centre (26.6° off the axis): the same flux through the same exact face
    /// solid angles, but the light keeps its direction. lightlab's default.
    #[default]
    Central,
}

crate::named_enum!(Reemit, "re-emission", {
    Central => "central",
    FaceNormal => "face",
}, aliases { "face-normal" => FaceNormal });

/// What becomes of the light the geometry volume blocks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Bounces {
    /// It is absorbed: the volume carries one bounce (Kaplanyan & Dachsbacher's default).
    Single,
    /// It is reflected back into the cell it came from, × the blocking surfaces' albedo, as a
    /// cosine lobe facing back (CLPV §5.3's multiple bounces): light keeps bouncing for as many
    /// steps as the propagation runs. lightlab's default.
    #[default]
    Multiple,
}

crate::named_enum!(Bounces, "bounce mode", {
    Single => "single",
    Multiple => "multiple",
});

/// The re-emission lobe's band-1 weight, relative to a delta's, of Kaplanyan's clamped cosine
/// (its 2-band projection is (Y₀₀, ⅔·C₁·n) per unit flux).
pub const COSINE_LOBE: f32 = 2.0 / 3.0;

/// lightlab's default re-emission lobe for [`Reemit::Central`]'s side faces (see
/// [`reemission_lobe`]): between Kaplanyan's cosine (⅔, too diffusive) and the 2-band
/// projection of the narrow cone of light that crosses a side face (its mean cosine, 0.97;
/// at 1 the lobes' negative back halves grow until a closed room loses its light). Chosen over
/// the four demo scenes (docs/lpv.md, *Measured*).
pub const DEFAULT_REEMIT_LOBE: f32 = 0.85;

/// A unit-flux lobe around `axis` whose band-1 weight is `lobe` times a delta's: [`COSINE_LOBE`]
/// gives cosine_lobe(axis)/π; larger values keep the light's direction better.
pub fn reemission_lobe(axis: Vec3, lobe: f32) -> Sh4 {
    let k = lobe * C1;
    [Y00, k * axis.y, k * axis.z, k * axis.x]
}

/// One propagation step (Kaplanyan's 6-face scheme, the side faces' light re-emitted as
/// `reemit` says, with [`Reemit::Central`] as a lobe of band-1 weight `lobe`, see
/// [`reemission_lobe`]): returns only the newly arrived light. With an occlusion volume, light
/// crossing into the receiving cell is attenuated by its transmittance, and with
/// [`Bounces::Multiple`] what the face blocks is reflected ([`reflected`]).
pub fn propagate_step(
    src: &Volume,
    occlusion: Option<&Occlusion>,
    reemit: Reemit,
    lobe: f32,
    bounces: Bounces,
) -> Volume {
    let g = src.grid;
    // Per axis d, the receiving cell's 5 faces: the direction from the source centre to the
    // face centre, and the re-emitted unit-flux lobe scaled by ΔΩ: the far face's a cosine
    // lobe along d; a side face's a cosine lobe around its normal (`FaceNormal`) or a lobe of
    // weight `lobe` along that direction (`Central`).
    let faces: [[(Vec3, Sh4); 5]; 6] = AXES.map(|d| {
        let dv = d.as_vec3();
        let mut f = [(
            dv,
            scaled(&cosine_lobe(dv), SOLID_ANGLE_FAR / std::f32::consts::PI),
        ); 5];
        let sides = AXES.iter().filter(|s| **s != d && **s != -d);
        for (k, side) in sides.enumerate() {
            let sv = side.as_vec3();
            let w = (dv + 0.5 * sv).normalize();
            let shape = match reemit {
                Reemit::FaceNormal => reemission_lobe(sv, COSINE_LOBE),
                Reemit::Central => reemission_lobe(w, lobe),
            };
            f[k + 1] = (w, scaled(&shape, SOLID_ANGLE_SIDE));
        }
        f
    });
    let mut out = Volume::new(g);
    for c in g.cells() {
        let mut acc = [[0.0f32; 4]; 3];
        for (d, faces) in AXES.iter().zip(&faces) {
            let s = c - *d;
            if !g.contains(s) {
                continue;
            }
            let from = src.at(s);
            let t = occlusion.map_or(1.0, |o| o.transmittance(s, *d, d.as_vec3()));
            if t <= 0.0 {
                continue;
            }
            for (w, lobe) in faces {
                for ch in 0..3 {
                    add_to(&mut acc[ch], lobe, t * eval(&from[ch], *w));
                }
            }
        }
        if let (Some(o), Bounces::Multiple) = (occlusion, bounces) {
            reflected(src, o, c, &faces, &mut acc);
        }
        out.cells[g.index(c)] = acc;
    }
    out
}

/// Multiple bounces (Kaplanyan & Dachsbacher 2010, §5.3), in gather form: the light cell `c`
/// sends towards each neighbour the flux Σ_f ΔΩ_f·I(ω_f) over that neighbour's five faces
/// (what the neighbour gathers); the part its shared face blocks, 1 − T, meets a surface and
/// comes back into `c` × the face's albedo, as a cosine lobe facing back along −axis. Only
/// light that was blocked is reflected, and at most all of it, so the step still conserves
/// flux for albedos ≤ 1.
fn reflected(src: &Volume, o: &Occlusion, c: IVec3, faces: &[[(Vec3, Sh4); 5]; 6], acc: &mut Cell) {
    let own = src.at(c);
    for (d, faces) in AXES.iter().zip(faces) {
        if !src.grid.contains(c + *d) {
            continue;
        }
        let dv = d.as_vec3();
        let blocked = 1.0 - o.transmittance(c, *d, dv);
        if blocked <= 0.0 {
            continue;
        }
        let rho = o.face_albedo(c, *d) * blocked;
        let lobe = scaled(&cosine_lobe(-dv), 1.0 / std::f32::consts::PI);
        for ch in 0..3 {
            let flux: f32 = faces
                .iter()
                .enumerate()
                .map(|(k, (w, _))| {
                    let solid = if k == 0 {
                        SOLID_ANGLE_FAR
                    } else {
                        SOLID_ANGLE_SIDE
                    };
                    solid * eval(&own[ch], *w)
                })
                .sum();
            add_to(&mut acc[ch], &lobe, rho[ch] * flux.max(0.0));
        }
    }
}

/// Seed plus `iterations` propagation steps, accumulated. Occlusion (if any) is skipped on the
/// first step, as Kaplanyan & Dachsbacher do against self-shadowing.
pub fn propagate(
    seed: &Volume,
    occlusion: Option<&Occlusion>,
    iterations: u32,
    reemit: Reemit,
    lobe: f32,
    bounces: Bounces,
) -> Volume {
    let mut acc = seed.clone();
    let mut cur = seed.clone();
    for i in 0..iterations {
        let occ = if i == 0 { None } else { occlusion };
        cur = propagate_step(&cur, occ, reemit, lobe, bounces);
        acc.accumulate(&cur);
    }
    acc
}

/// The WPI report's propagation falloff f.
pub const WPI_FALLOFF: f32 = 0.65;

/// One step of the WPI report's propagation (faithful to its shader): each cell adds, from its
/// 6 face (weight 1) and 12 edge (weight ½) neighbours, f·w·max(0, I_n(d))·Y(d)/18 with d the
/// direction from the neighbour towards the cell, to its own previous value; borders clamp.
pub fn propagate_step_wpi(src: &Volume) -> Volume {
    let g = src.grid;
    let n = g.n as i32;
    let mut out = src.clone();
    let mut offsets = Vec::with_capacity(18);
    for d in AXES {
        offsets.push((d, 1.0f32));
    }
    for a in 0..3 {
        for b in (a + 1)..3 {
            for sa in [-1, 1] {
                for sb in [-1, 1] {
                    let mut o = IVec3::ZERO;
                    o[a] = sa;
                    o[b] = sb;
                    offsets.push((o, 0.5));
                }
            }
        }
    }
    for c in g.cells() {
        let mut acc = [[0.0f32; 4]; 3];
        for &(o, w) in &offsets {
            let nb = (c + o).clamp(IVec3::ZERO, IVec3::splat(n - 1));
            let d = -o.as_vec3().normalize();
            let y = basis(d);
            let from = src.at(nb);
            for ch in 0..3 {
                let i = dot(&from[ch], &y).max(0.0);
                add_to(&mut acc[ch], &y, WPI_FALLOFF * w * i);
            }
        }
        let cell = &mut out.cells[g.index(c)];
        for ch in 0..3 {
            add_to(&mut cell[ch], &acc[ch], 1.0 / 18.0);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn grid(n: u32) -> Grid {
        Grid {
            n,
            origin: Vec3::ZERO,
            cell: 1.0,
        }
    }

    /// The solid angle of a rectangle [x0,x1]×[y0,y1] at distance h (exact, Van Oosterom form).
    fn rect_solid_angle(x0: f64, x1: f64, y0: f64, y1: f64, h: f64) -> f64 {
        let f = |x: f64, y: f64| (x * y / (h * (x * x + y * y + h * h).sqrt())).atan();
        f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
    }

    #[test]
    fn face_solid_angles_are_exact() {
        // Far face: a unit square at distance 1.5 from the source centre.
        let far = rect_solid_angle(-0.5, 0.5, -0.5, 0.5, 1.5);
        assert!((far - 4.0 * (1.0f64 / (1.0 + 4.0 * 1.5 * 1.5)).asin()).abs() < 1e-9);
        assert!((far - SOLID_ANGLE_FAR as f64).abs() < 1e-6, "{far}");
        // Side face: plane at distance 0.5, spanning [0.5, 1.5] along the axis and [−.5, .5].
        let side = rect_solid_angle(0.5, 1.5, -0.5, 0.5, 0.5);
        assert!((side - SOLID_ANGLE_SIDE as f64).abs() < 1e-6, "{side}");
        // Far + 4 sides = the shared face seen from the source centre = 2π/3.
        assert!((far + 4.0 * side - 2.0 * PI / 3.0).abs() < 1e-9);
    }

    #[test]
    fn lobes_project_as_expected() {
        // Integrate max(0, n·ω)·Y_i(ω) numerically over a fine lat-long grid.
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let (nt, np) = (400, 800);
        let mut c = [0.0f64; 4];
        for i in 0..nt {
            let th = (i as f64 + 0.5) * PI / nt as f64;
            for j in 0..np {
                let ph = (j as f64 + 0.5) * 2.0 * PI / np as f64;
                let w = Vec3::new(
                    (th.sin() * ph.cos()) as f32,
                    (th.sin() * ph.sin()) as f32,
                    th.cos() as f32,
                );
                let f = n.dot(w).max(0.0) as f64;
                let y = basis(w);
                let dw = th.sin() * (PI / nt as f64) * (2.0 * PI / np as f64);
                for k in 0..4 {
                    c[k] += f * y[k] as f64 * dw;
                }
            }
        }
        let want = cosine_lobe(n);
        for k in 0..4 {
            assert!(
                (c[k] - want[k] as f64).abs() < 2e-4,
                "{k}: {} vs {}",
                c[k],
                want[k]
            );
        }
        // The projected lobe integrates to π; a delta evaluated at its direction gives 1/π.
        assert!((want[0] as f64 * 4.0 * PI * Y00 as f64 - PI).abs() < 1e-5);
        let d = Vec3::new(0.0, 0.6, 0.8);
        assert!((eval(&basis(d), d) as f64 - 1.0 / PI).abs() < 1e-6);
        // WPI's worked example (Eq 3.11–3.12): six axis samples of 0.8 → c₀ = 2.835926, back to 0.8.
        let c0 = 4.0 * PI / 6.0 * 6.0 * 0.8 * Y00 as f64;
        assert!((c0 - 2.835_926_164).abs() < 1e-6);
        assert!((c0 * Y00 as f64 - 0.8).abs() < 1e-6);
    }

    #[test]
    fn six_face_propagation_conserves_flux() {
        let g = grid(17);
        let mid = IVec3::splat(8);
        for normal in [
            Vec3::Y,
            Vec3::new(0.6, 0.0, -0.8),
            Vec3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let vpl = Vpl {
                position: g.centre(mid),
                normal,
                flux: Vec3::new(1.0, 2.0, 0.5),
            };
            let seed = inject(
                g,
                &[Vpl {
                    position: vpl.position - 0.5 * normal,
                    ..vpl
                }],
            );
            let f0 = seed.total_flux();
            assert!((f0 - vpl.flux).abs().max_element() < 1e-5, "{f0}");
            // Any lobe carries its unit flux in the constant term: the step conserves flux
            // whatever the re-emission.
            for (reemit, lobe) in [
                (Reemit::FaceNormal, COSINE_LOBE),
                (Reemit::Central, COSINE_LOBE),
                (Reemit::Central, DEFAULT_REEMIT_LOBE),
                (Reemit::Central, 1.0),
            ] {
                let mut cur = seed.clone();
                for it in 0..6 {
                    cur = propagate_step(&cur, None, reemit, lobe, Bounces::Single);
                    let f = cur.total_flux();
                    let err = ((f - vpl.flux) / vpl.flux).abs().max_element();
                    assert!(
                        err < 0.01,
                        "{reemit:?} {lobe}, iteration {it}: {f} vs {}",
                        vpl.flux
                    );
                }
            }
        }
    }

    #[test]
    fn wpi_propagation_matches_the_reports_regression_values() {
        // Extraction §5.5: isotropic seed DC = 1 on 9³.
        let g = grid(9);
        let mut v = Volume::new(g);
        let mid = IVec3::splat(4);
        v.cells[g.index(mid)] = [[1.0, 0.0, 0.0, 0.0]; 3];
        let k = 1.0 / (4.0 * std::f32::consts::PI * Y00); // flux → DC sum
        let totals = [1.0345, 1.0706, 1.1084, 1.1479];
        for (it, want) in totals.iter().enumerate() {
            v = propagate_step_wpi(&v);
            let dc = v.total_flux().x * k;
            assert!(
                (dc - want).abs() < 6e-4,
                "iteration {}: {dc} vs {want}",
                it + 1
            );
            assert!((v.at(mid)[0][0] - 1.0).abs() < 1e-6, "the seed is kept");
            let nb = v.at(mid + IVec3::X)[0][0];
            assert!(
                (nb - (it as f32 + 1.0) * 0.002_873_7).abs() < 2e-5 * (it as f32 + 1.0),
                "{nb}"
            );
        }
        // A delta towards +x reaches only the +x side: 0.003243 per pass.
        let mut v = Volume::new(g);
        v.cells[g.index(mid)] = [basis(Vec3::X); 3];
        v = propagate_step_wpi(&v);
        let plus = v.at(mid + IVec3::X)[0][0];
        assert!((plus - 0.003_243).abs() < 2e-6, "{plus}");
        assert_eq!(v.at(mid - IVec3::X)[0][0], 0.0);
    }

    #[test]
    fn the_unnormalised_scheme_fails_conservation_and_the_six_face_scheme_passes() {
        let g = grid(11);
        let mut v = Volume::new(g);
        v.cells[g.index(IVec3::splat(5))] = [[1.0, 0.0, 0.0, 0.0]; 3];
        let f0 = v.total_flux().x;
        let wpi = propagate_step_wpi(&propagate_step_wpi(&v)).total_flux().x;
        let six = propagate_step(
            &propagate_step(&v, None, Reemit::FaceNormal, COSINE_LOBE, Bounces::Single),
            None,
            Reemit::FaceNormal,
            COSINE_LOBE,
            Bounces::Single,
        )
        .total_flux()
        .x;
        assert!((wpi / f0 - 1.0).abs() > 0.05, "WPI grows: {}", wpi / f0);
        assert!(
            (six / f0 - 1.0).abs() < 0.01,
            "6-face conserves: {}",
            six / f0
        );
    }

    #[test]
    fn injection_shifts_half_a_cell_along_the_normal() {
        let g = grid(4);
        // On the boundary between cells x=1 and x=2, facing +x: lands in x=2.
        let v = inject(
            g,
            &[Vpl {
                position: Vec3::new(2.0, 1.5, 1.5),
                normal: Vec3::X,
                flux: Vec3::ONE,
            }],
        );
        assert!(v.at(IVec3::new(2, 1, 1))[0][0] > 0.0);
        assert_eq!(v.at(IVec3::new(1, 1, 1))[0][0], 0.0);
        // Facing −x: lands in x=1.
        let v = inject(
            g,
            &[Vpl {
                position: Vec3::new(2.0, 1.5, 1.5),
                normal: -Vec3::X,
                flux: Vec3::ONE,
            }],
        );
        assert!(v.at(IVec3::new(1, 1, 1))[0][0] > 0.0);
    }

    /// A plane of surfels of `albedo` at x = 5 facing −x, covering the 10-cell grid's face.
    fn wall_at_x5(albedo: Vec3) -> Vec<Surfel> {
        let mut surfels = Vec::new();
        for y in 0..40 {
            for z in 0..40 {
                surfels.push(Surfel {
                    position: Vec3::new(5.0, y as f32 * 0.25, z as f32 * 0.25),
                    normal: -Vec3::X,
                    area: 0.0625,
                    albedo,
                });
            }
        }
        surfels
    }

    #[test]
    fn a_wall_of_blockers_stops_light_from_both_sides() {
        // A plane of surfels at x = 5 facing −x fills the geometry cells there; light
        // travelling +x from x < 5 is stopped, and so is light from behind the plane (a
        // surface is opaque from both sides, though the RSM saw only one).
        let g = grid(10);
        let occ = Occlusion::inject(g, &wall_at_x5(Vec3::splat(0.5)));
        let c = IVec3::new(4, 5, 5);
        let t_in = occ.transmittance(c, IVec3::X, Vec3::X);
        assert!(t_in < 0.05, "{t_in}");
        let t_back = occ.transmittance(IVec3::new(5, 5, 5), -IVec3::X, -Vec3::X);
        assert!(t_back < 0.05, "{t_back}");
        // Light travelling along the wall crosses faces the wall does not lie in.
        let along = occ.transmittance(IVec3::new(2, 5, 5), IVec3::Y, Vec3::Y);
        assert_eq!(along, 1.0);
        // Elsewhere the volume is clear.
        assert_eq!(
            occ.transmittance(IVec3::new(2, 5, 5), IVec3::X, Vec3::X),
            1.0
        );
    }

    /// Multiple bounces: light meeting a wall of albedo ½ comes back into its cell as a lobe
    /// facing away from the wall, carrying ½ × what the wall blocked of the flux the cell sent
    /// towards it (measured as what the neighbour receives without the wall); nothing is
    /// created (the step's output flux ≤ its input).
    #[test]
    fn a_wall_reflects_what_it_blocks_times_its_albedo() {
        let g = grid(10);
        let occ = Occlusion::inject(g, &wall_at_x5(Vec3::new(0.5, 0.25, 0.0)));
        let c = IVec3::new(4, 5, 5);
        assert!((occ.face_albedo(c, IVec3::X) - Vec3::new(0.5, 0.25, 0.0)).length() < 1e-5);
        assert_eq!(occ.face_albedo(IVec3::new(2, 5, 5), IVec3::X), Vec3::ZERO);
        let mut v = Volume::new(g);
        let lobe = scaled(&cosine_lobe(Vec3::X), 1.0 / std::f32::consts::PI);
        v.cells[g.index(c)] = [lobe; 3];
        let k = 4.0 * std::f32::consts::PI * Y00;
        let free = propagate_step(
            &v,
            None,
            Reemit::Central,
            DEFAULT_REEMIT_LOBE,
            Bounces::Single,
        );
        assert!(1.0 - occ.transmittance(c, IVec3::X, Vec3::X) > 0.95);
        // Σ over the six faces of blocked × sent (the wall's corners touch the side faces too:
        // a 2-band blocker's constant term blocks a little in every direction).
        let lost: f32 = AXES
            .iter()
            .map(|d| {
                let blocked = 1.0 - occ.transmittance(c, *d, d.as_vec3());
                blocked * free.at(c + *d)[0][0] * k
            })
            .sum();
        let single = propagate_step(
            &v,
            Some(&occ),
            Reemit::Central,
            DEFAULT_REEMIT_LOBE,
            Bounces::Single,
        );
        let multi = propagate_step(
            &v,
            Some(&occ),
            Reemit::Central,
            DEFAULT_REEMIT_LOBE,
            Bounces::Multiple,
        );
        let back = multi.at(c);
        for (ch, rho) in [0.5f32, 0.25, 0.0].into_iter().enumerate() {
            let want = rho * lost;
            let got = back[ch][0] * k;
            assert!(
                (got - want).abs() < 1e-4 + 1e-3 * want,
                "{ch}: {got} vs {want}"
            );
            // Facing −x (Y11 ∝ x is the fourth coefficient).
            assert!(back[ch][3] <= 0.0);
        }
        assert_eq!(single.at(c)[0], [0.0; 4]);
        let (fm, f0) = (multi.total_flux(), v.total_flux());
        assert!(fm.x <= f0.x && fm.x > single.total_flux().x, "{fm} vs {f0}");
    }

    #[test]
    fn irradiance_of_a_uniform_field() {
        // Isotropic intensity I in every cell: radiance I/s², irradiance π·I/s² on any normal.
        let g = Grid {
            n: 4,
            origin: Vec3::ZERO,
            cell: 0.5,
        };
        let mut v = Volume::new(g);
        let i = 2.0;
        for c in &mut v.cells {
            // I(ω) = c₀·Y₀₀ = i.
            *c = [[i / Y00, 0.0, 0.0, 0.0]; 3];
        }
        let e = v.irradiance(Vec3::splat(1.0), Vec3::new(0.0, 0.6, 0.8));
        let want = std::f32::consts::PI * i / 0.25;
        assert!((e.x - want).abs() < 1e-3 * want, "{e} vs {want}");
    }

    #[test]
    fn damping_removes_a_floors_own_light_and_keeps_light_from_above() {
        // A lit floor (VPLs facing +y on y = 2) lights itself through the lobes that spread
        // sideways; a source 8 cells above the floor is light from elsewhere.
        let g = grid(16);
        let mut floor = Vec::new();
        for x in 0..16 {
            for z in 0..16 {
                floor.push(Vpl {
                    position: Vec3::new(x as f32 + 0.5, 2.0, z as f32 + 0.5),
                    normal: Vec3::Y,
                    flux: Vec3::ONE,
                });
            }
        }
        let own = propagate(
            &inject(g, &floor),
            None,
            8,
            Reemit::FaceNormal,
            COSINE_LOBE,
            Bounces::Single,
        );
        let p = Vec3::new(8.0, 2.0, 8.0);
        let plain = own.irradiance(p, Vec3::Y).x;
        let damped = own.irradiance_damped(p, Vec3::Y, 2.0).x;
        assert!(plain > 0.0);
        assert!(damped < 0.6 * plain, "{damped} vs {plain}");
        let above = [Vpl {
            position: Vec3::new(8.0, 10.0, 8.0),
            normal: -Vec3::Y,
            flux: Vec3::ONE,
        }];
        let other = propagate(
            &inject(g, &above),
            None,
            8,
            Reemit::FaceNormal,
            COSINE_LOBE,
            Bounces::Single,
        );
        let plain = other.irradiance(p, Vec3::Y).x;
        let damped = other.irradiance_damped(p, Vec3::Y, 2.0).x;
        assert!(plain > 0.0);
        assert!(damped > 0.9 * plain, "{damped} vs {plain}");
        // No damping: the plain lookup.
        assert_eq!(
            other.irradiance_damped(p, Vec3::Y, 0.0),
            other.irradiance(p, Vec3::Y)
        );
    }

    #[test]
    fn cascades_nest_and_do_not_move_for_sub_cell_camera_moves() {
        let scene = Grid::around(Vec3::ZERO, Vec3::splat(10.0), 16, 1.0);
        let eye = Vec3::new(3.3, 2.1, 4.7);
        let fwd = Vec3::new(0.3, -0.2, 1.0);
        let a = cascade_grids(scene, 3, eye, fwd, true);
        assert_eq!(a.len(), 3);
        assert_eq!(a[2], scene);
        assert!((a[1].cell - scene.cell / 2.0).abs() < 1e-6);
        assert!((a[0].cell - scene.cell / 4.0).abs() < 1e-6);
        // Origins on whole cells of each grid.
        for g in &a[..2] {
            let k = g.origin / g.cell;
            assert!((k - k.round()).abs().max_element() < 1e-3, "{k}");
        }
        // Moves of a fraction of the finest cell: every grid keeps its lattice (it stays or
        // shifts by one whole cell where the move crosses a cell boundary).
        for k in 1..10 {
            let d = Vec3::new(0.37, -0.11, 0.23) * k as f32 * a[0].cell;
            let b = cascade_grids(scene, 3, eye + d, fwd, true);
            for (ga, gb) in a.iter().zip(&b) {
                assert_eq!(ga.cell, gb.cell);
                let shift = (gb.origin - ga.origin) / ga.cell;
                assert!(
                    (shift - shift.round()).abs().max_element() < 1e-3,
                    "{shift}"
                );
                let moved = (d / ga.cell).abs().max_element();
                assert!(shift.abs().max_element() <= moved.ceil() + 1e-3, "{shift}");
            }
        }
        // Unsnapped, the fine grids follow the eye off the lattice.
        let u0 = cascade_grids(scene, 3, eye, fwd, false);
        let u = cascade_grids(scene, 3, eye + Vec3::X * 0.33 * a[0].cell, fwd, false);
        let shift = (u[0].origin - u0[0].origin) / a[0].cell;
        assert!((shift - shift.round()).abs().max_element() > 0.1, "{shift}");
        // The eye's neighbourhood reads the finest grid; far away, the scene's.
        let (c, w) = cascade_weight(
            &a,
            eye + fwd.normalize() * 0.25 * 16.0 * a[0].cell,
            2.0,
            2.0,
        );
        assert_eq!((c, w), (0, 1.0));
        assert_eq!(cascade_weight(&a, Vec3::splat(-0.5), 2.0, 2.0).0, 2);
    }

    #[test]
    fn two_band_transport_is_diffusive() {
        // What limits an LPV's reach (docs/lpv.md): a VPL's light does not stream outwards at a
        // cell per step but diffuses. One cosine lobe facing +y: after t steps the flux's mean
        // distance grows like √t with Kaplanyan's face-normal re-emission, and the accumulated
        // irradiance straight above falls well below the inverse-square law beyond a few cells.
        // Re-emitting along the light's own direction (Reemit::Central) keeps it going.
        let g = grid(33);
        let src = IVec3::new(16, 2, 16);
        let vpl = Vpl {
            position: g.centre(src) - 0.5 * Vec3::Y,
            normal: Vec3::Y,
            flux: Vec3::ONE,
        };
        let seed = inject(g, &[vpl]);
        let run = |reemit: Reemit, lobe: f32| {
            let mut cur = seed.clone();
            let mut acc = seed.clone();
            let mut radius = vec![];
            for _ in 0..16 {
                cur = propagate_step(&cur, None, reemit, lobe, Bounces::Single);
                acc.accumulate(&cur);
                let (mut m, mut w) = (0.0f64, 0.0f64);
                for c in g.cells() {
                    let f = cur.at(c)[0][0] as f64;
                    m += f * (c - src).as_vec3().length() as f64;
                    w += f;
                }
                radius.push(m / w);
            }
            // E·π·r²/Φ above the source on a receiver facing it: 1 for the exact inverse square
            // law.
            let ratio = |r: i32| {
                let p = g.centre(src + IVec3::new(0, r, 0)) - 0.5 * Vec3::Y;
                acc.irradiance(p, -Vec3::Y).x * std::f32::consts::PI * (r as f32).powi(2)
            };
            let r = [ratio(2), ratio(4), ratio(8)];
            eprintln!(
                "{reemit:?} {lobe:.2}: mean distance of the flux after 1, 4, 9, 16 steps: \
                 {:.2} {:.2} {:.2} {:.2}; E·πr²/Φ straight above at 2, 4, 8 cells: {:.3} {:.3} \
                 {:.3} (exact: 1)",
                radius[0], radius[3], radius[8], radius[15], r[0], r[1], r[2]
            );
            (radius, r)
        };
        let (radius, r) = run(Reemit::FaceNormal, COSINE_LOBE);
        // Free streaming would put it at t cells; diffusion at ∝ √t.
        assert!(
            radius[15] < 6.0 && radius[15] > 2.0 * radius[0],
            "{radius:?}"
        );
        assert!(r[0] > 0.5 && r[2] < 0.4 * r[0], "{r:?}");
        // Measured: 4.23 cells after 16 steps and 0.08 at 8 cells (face normal) against 7.41
        // and 0.88 (central, cosine lobes); a sharper lobe carries light further still.
        let (central, rc) = run(Reemit::Central, COSINE_LOBE);
        assert!(central[15] > 1.5 * radius[15], "{central:?}");
        assert!(rc[2] > 5.0 * r[2] && rc[2] > 0.6, "{rc:?}");
        let (sharp, rs) = run(Reemit::Central, DEFAULT_REEMIT_LOBE);
        assert!(sharp[15] > central[15], "{sharp:?}");
        assert!(rs[2] > rc[2], "{rs:?}");
    }

    #[test]
    fn the_cosine_reemission_lobe_is_kaplanyans() {
        for axis in [Vec3::X, Vec3::new(0.48, -0.6, 0.64)] {
            let a = reemission_lobe(axis, COSINE_LOBE);
            let b = scaled(&cosine_lobe(axis), 1.0 / std::f32::consts::PI);
            for k in 0..4 {
                assert!((a[k] - b[k]).abs() < 1e-6, "{a:?} vs {b:?}");
            }
        }
    }
}
