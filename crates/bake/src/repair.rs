//! Border repair (Fuchs §3.3.6 step 1): texels without a valid value (outside every polygon, or
//! invalidated because their sample saw back faces) take the weighted average of their valid
//! 8-neighbours (edges ½, corners ¼ as in CaLight), ring by ring, so bilinear and bicubic
//! sampling at polygon edges never reads black. Filling proceeds outward from valid texels one
//! ring at a time, so a texel under a wall takes its value from the nearer side: with walls at
//! least two texels thick, light does not cross them.

use glam::Vec3;

/// Fill invalid texels of one page from valid neighbours, up to `rings` rings out.
pub fn dilate(values: &mut [Vec3], valid: &mut [bool], width: u32, height: u32, rings: u32) {
    let (w, h) = (width as i32, height as i32);
    for _ in 0..rings {
        let mut updates: Vec<(usize, Vec3)> = vec![];
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if valid[i] {
                    continue;
                }
                let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let j = (ny * w + nx) as usize;
                        if valid[j] {
                            let wt = if dx == 0 || dy == 0 { 0.5 } else { 0.25 };
                            sum += values[j] * wt;
                            wsum += wt;
                        }
                    }
                }
                if wsum > 0.0 {
                    updates.push((i, sum / wsum));
                }
            }
        }
        if updates.is_empty() {
            break;
        }
        for (i, v) in updates {
            values[i] = v;
            valid[i] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_fills_ring_by_ring_from_the_nearer_side() {
        // A row: lit | 4 invalid | dark. The two invalid texels next to each side take that
        // side's value.
        let mut v = vec![
            Vec3::ONE,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::splat(0.0),
        ];
        let mut ok = vec![true, false, false, false, false, true];
        dilate(&mut v, &mut ok, 6, 1, 8);
        assert!(ok.iter().all(|&b| b));
        assert_eq!(v[1], Vec3::ONE);
        assert_eq!(v[4], Vec3::ZERO);
        // Ring 2: texels 2 and 3 are each next to one filled texel only.
        assert_eq!(v[2], Vec3::ONE);
        assert_eq!(v[3], Vec3::ZERO);
    }
}
