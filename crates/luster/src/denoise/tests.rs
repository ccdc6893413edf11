//! Unit tests of the denoiser: argument checks in every build; with the
//! `oidn` feature, what OIDN does with synthetic noisy images whose clean
//! image is known.

use super::*;

#[test]
fn buffers_of_the_wrong_size_or_a_lone_normal_are_refused() {
    let px = vec![Vec3::ONE; 6];
    let short = vec![Vec3::ONE; 5];
    assert!(check_sizes(3, 2, &px, Some(&px), Some(&px)).is_ok());
    let e = check_sizes(3, 2, &short, None, None).unwrap_err();
    assert!(e.contains("colour image has 5 pixels, not 3x2"), "{e}");
    let e = check_sizes(3, 2, &px, Some(&short), None).unwrap_err();
    assert!(e.contains("albedo image has 5 pixels"), "{e}");
    let e = check_sizes(3, 2, &px, Some(&px), Some(&short)).unwrap_err();
    assert!(e.contains("normal image has 5 pixels"), "{e}");
    let e = check_sizes(3, 2, &px, None, Some(&px)).unwrap_err();
    assert!(e.contains("no albedo"), "{e}");
    assert!(check_sizes(0, 2, &[], None, None).unwrap_err().contains("no pixels"));
}

#[cfg(not(feature = "oidn"))]
#[test]
fn without_the_feature_the_denoiser_says_how_to_build_it() {
    let e = Denoiser::new(1).err().expect("no denoiser without the feature");
    assert!(e.contains("--features oidn"), "{e}");
}

#[cfg(feature = "oidn")]
mod with_oidn {
    use super::*;

    /// A uniform number in [0, 1) from `(i, seed)` (splitmix64).
    fn uniform(i: u64, seed: u64) -> f32 {
        let mut z = i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ seed.wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    /// `clean` with Monte-Carlo-like noise of mean 1 per pixel: each value
    /// times an average of `k` exponential variates (a few samples of a
    /// light that is hit or missed).
    fn noisy(clean: &[Vec3], k: u32, seed: u64) -> Vec<Vec3> {
        clean
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let m: f32 =
                    (0..k).map(|j| -(1.0 - uniform(i as u64 * 64 + u64::from(j), seed)).ln()).sum::<f32>()
                        / k as f32;
                c * m
            })
            .collect()
    }

    fn rmse(a: &[Vec3], b: &[Vec3]) -> f32 {
        (a.iter().zip(b).map(|(x, y)| (*x - *y).length_squared()).sum::<f32>() / (3.0 * a.len() as f32))
            .sqrt()
    }

    fn mean(a: &[Vec3]) -> f32 {
        a.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / (3.0 * a.len() as f32)
    }

    const W: u32 = 96;
    const H: u32 = 64;

    /// A checkerboard albedo (8-pixel squares, 0.2 and 0.8) under a
    /// horizontal light gradient, in film units (255 = white).
    fn checker() -> (Vec<Vec3>, Vec<Vec3>) {
        let mut albedo = Vec::new();
        let mut clean = Vec::new();
        for y in 0..H {
            for x in 0..W {
                let a = if (x / 8 + y / 8) % 2 == 0 { Vec3::new(0.8, 0.7, 0.6) } else { Vec3::splat(0.2) };
                albedo.push(a);
                clean.push(a * (120.0 + 100.0 * x as f32 / W as f32));
            }
        }
        (albedo, clean)
    }

    #[test]
    fn denoising_a_noisy_image_brings_it_near_the_clean_one_and_keeps_its_mean() {
        let (_, clean) = checker();
        let n = noisy(&clean, 4, 1);
        let d = denoise(W, H, &n, None, None).expect("denoised");
        assert_eq!(d.len(), clean.len());
        assert!(d.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
        let (before, after) = (rmse(&n, &clean), rmse(&d, &clean));
        assert!(after < before / 2.0, "RMSE {before} noisy, {after} denoised");
        let (m, mc) = (mean(&d), mean(&clean));
        assert!((m - mc).abs() < 0.03 * mc, "mean {m} denoised, {mc} clean");
    }

    #[test]
    fn an_albedo_buffer_keeps_texture_edges_the_noise_hides() {
        let (albedo, clean) = checker();
        // Heavy noise: the checker's edges are lost in it without the albedo.
        let n = noisy(&clean, 1, 2);
        let plain = denoise(W, H, &n, None, None).expect("denoised");
        let guided = denoise(W, H, &n, Some(&albedo), None).expect("denoised with albedo");
        let normals = vec![Vec3::Z; albedo.len()];
        let both = denoise(W, H, &n, Some(&albedo), Some(&normals)).expect("denoised with albedo and normal");
        let (p, g, b) = (rmse(&plain, &clean), rmse(&guided, &clean), rmse(&both, &clean));
        assert!(g < 0.7 * p, "RMSE {p} without albedo, {g} with");
        assert!(b < 0.7 * p, "RMSE {p} without albedo, {b} with albedo and normal");
    }

    #[test]
    fn nan_infinite_and_negative_pixels_become_black_not_a_blot() {
        let grey = vec![Vec3::splat(100.0); (W * H) as usize];
        let mut n = noisy(&grey, 8, 3);
        let centre = (H / 2 * W + W / 2) as usize;
        n[centre] = Vec3::new(f32::NAN, 1.0, 1.0);
        n[centre + 10] = Vec3::splat(f32::INFINITY);
        n[centre + 20] = Vec3::splat(-50.0);
        let d = denoise(W, H, &n, None, None).expect("denoised");
        assert!(d.iter().all(|p| p.is_finite()));
        // A lone black pixel is noise to the network, filled from its neighbours.
        for i in [centre, centre + 10, centre + 20, 0] {
            assert!((d[i] - Vec3::splat(100.0)).abs().max_element() < 25.0, "pixel {i}: {}", d[i]);
        }
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let (albedo, clean) = checker();
        let n = noisy(&clean, 2, 4);
        let one = Denoiser::new(1).expect("device").denoise(W, H, &n, Some(&albedo), None).expect("denoised");
        let four =
            Denoiser::new(4).expect("device").denoise(W, H, &n, Some(&albedo), None).expect("denoised");
        assert!(one
            .iter()
            .zip(&four)
            .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)));
    }
}
