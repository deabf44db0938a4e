//! The display image of a multi-view display, each subpixel from its own
//! eye: one ray a subpixel gives exactly the naive interleaving
//! of separately rendered views, at any number of views; the geometric +
//! spectral passes match it but for a stated share of subpixels, for
//! little more than one view's field evaluations, while the naive cost
//! grows with the number of views (counted, not timed); shading green's
//! hit for red and blue costs one view and leaves more subpixels off.

use crate::common;

use anari_library_caveray::cave::MultiViewDisplay;
use anari_library_caveray::render::iso::{
    render_display, subpixels_differing, IsoSettings, MultiViewMethod,
};
use anari_library_caveray::scene::PlacedVolume;
use glam::{Mat4, Vec3};

/// The two balls, 1.2 m behind the panel.
fn scene() -> PlacedVolume {
    common::iso::two_balls(40, Mat4::from_translation(Vec3::new(0.0, 0.0, -1.2)))
}

/// A small panel of `views` views (metres), the shipped lens pattern.
fn display(views: u32) -> MultiViewDisplay {
    // The shipped lens, rescaled so that a lens still spans 8 views' worth
    // of pattern for any view count (pitch in subpixels per `views`).
    let pitch = 3.75 * f64::from(views) / 8.0;
    let text = format!(
        "units = \"m\"\nviews = {views}\nresolution = [48, 32]\n\
         ll = [-1.2, -0.8, 0.0]\nlr = [1.2, -0.8, 0.0]\nur = [1.2, 0.8, 0.0]\n\
         viewing_distance = 3.0\nview_spacing = 0.03\n\
         [lens]\npitch = {pitch}\nslant = 0.15625\n"
    );
    MultiViewDisplay::from_toml(&text, "test display").unwrap()
}

fn render(views: u32, method: MultiViewMethod) -> (anari_library_caveray::render::Frame, u64) {
    let d = display(views);
    let panel = common::iso::panel(&d);
    render_display(&scene(), &panel, &IsoSettings::new(0.5), method).unwrap()
}

#[test]
fn one_ray_a_subpixel_is_the_naive_interleaving_exactly() {
    for views in [1, 8, 24] {
        let (naive, _) = render(views, MultiViewMethod::Naive);
        let (per_subpixel, _) = render(views, MultiViewMethod::PerSubpixel);
        assert_eq!(per_subpixel.color, naive.color, "{views} views");
        // Something was hit, and the views differ from one another.
        assert!(naive.to_srgb8_top_down().chunks(4).any(|p| p[0] > 40));
    }
}

#[test]
fn the_spectral_pass_matches_all_but_a_few_subpixels_whatever_the_view_count() {
    let mut spectral_views = Vec::new();
    for views in [8, 24] {
        let (naive, naive_samples) = render(views, MultiViewMethod::Naive);
        let (_, per_subpixel_samples) = render(views, MultiViewMethod::PerSubpixel);
        let (spectral, spectral_samples) = render(views, MultiViewMethod::GeometricSpectral);
        let one_view = naive_samples as f64 / f64::from(views);
        let differ = subpixels_differing(&spectral, &naive, 2);
        println!(
            "{views} views: naive {:.2}, per subpixel {:.2}, geometric+spectral {:.2} views' evaluations; {:.3}% of subpixels differ",
            naive_samples as f64 / one_view,
            per_subpixel_samples as f64 / one_view,
            spectral_samples as f64 / one_view,
            100.0 * differ
        );
        assert!(
            differ <= 0.01,
            "{views} views: {differ} of subpixels differ"
        );
        // One ray a subpixel costs about three views; the passes about
        // half that, green's ray in full and the others from near its hit.
        assert!(per_subpixel_samples as f64 <= 3.2 * one_view);
        assert!(
            spectral_samples as f64 <= 0.6 * per_subpixel_samples as f64,
            "{views} views: {spectral_samples} evaluations vs {per_subpixel_samples} per subpixel"
        );
        spectral_views.push(spectral_samples as f64 / one_view);
    }
    // The passes' cost does not grow with the number of views.
    assert!(
        spectral_views[1] <= 1.15 * spectral_views[0],
        "{spectral_views:?} views' evaluations at 8 and 24 views"
    );
}

#[test]
fn shading_greens_hit_for_every_channel_costs_one_view_and_is_exact_only_for_one_view() {
    // One view: every channel's eye is green's, so green's hit is theirs.
    let (naive, _) = render(1, MultiViewMethod::Naive);
    let (green, _) = render(1, MultiViewMethod::GreenGeometry);
    assert_eq!(green.color, naive.color);
    for views in [8, 24] {
        let (naive, naive_samples) = render(views, MultiViewMethod::Naive);
        let (spectral, _) = render(views, MultiViewMethod::GeometricSpectral);
        let (green, green_samples) = render(views, MultiViewMethod::GreenGeometry);
        let one_view = naive_samples as f64 / f64::from(views);
        let (exact, reused) = (
            subpixels_differing(&spectral, &naive, 2),
            subpixels_differing(&green, &naive, 2),
        );
        println!(
            "{views} views: green's geometry {:.2} views' evaluations, {:.3}% of subpixels differ (the passes {:.3}%)",
            green_samples as f64 / one_view,
            100.0 * reused,
            100.0 * exact
        );
        // Only green's rays are cast; each pixel's from its own view, so
        // about, not exactly, one view's image.
        assert!(
            (green_samples as f64 - one_view).abs() <= 0.1 * one_view,
            "{views} views: {green_samples} evaluations, one view {one_view}"
        );
        // Red and blue show green's point, not their own: off on the balls'
        // shaded surfaces, where the passes are right.
        assert!(
            reused > 2.0 * exact && reused > 0.01,
            "{views} views: {reused} vs {exact}"
        );
        assert!(reused < 0.5, "{views} views: {reused}");
    }
}
