//! Rendered images, pinned: with Embree's kernel set pinned, an image is a
//! function of the scene, the settings and the code, like a photon map
//! (`isa_pinning.rs`). The checksums below were recorded before the
//! renderer's image loop was written once for both estimators
//! (`render/film.rs`) and its rays put behind the `RayCaster` seam; a change
//! that moves them changes what users render: record the new values here.
//!
//! Also: a caster of the user's renders the same image as Embree's.

use crate::fixtures::{cpu_vendor, OneByOne};
use adaptive_pm::embree::{CommittedScene, Device, EmbreeScene};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::isa::Isa;
use adaptive_pm::raycast::RayCaster;
use adaptive_pm::render::{
    render, render_path, GatherDirections, Image, PathPart, RenderConfig, RenderMaps, View,
};
use adaptive_pm::scene::{PreparedScene, Scene};

/// FNV-1a over the pixels' bits.
fn checksum(img: &Image) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for p in &img.pixels {
        for c in [p.x, p.y, p.z] {
            for b in c.to_bits().to_le_bytes() {
                h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
            }
        }
    }
    h
}

/// All four maps: the view without gather reads the indirect one.
fn maps<C: RayCaster>(tracer: &Tracer<C>) -> RenderMaps {
    let mut tc = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
    tc.seed = 7;
    RenderMaps::build(&tracer.trace(&tc).unwrap().records())
}

/// The five images of a scene: the default render, without gather, the
/// map view, direct light only, and the path tracer's.
fn images<C: RayCaster>(tracer: &Tracer<C>) -> [Image; 5] {
    let prepared: &PreparedScene<C> = tracer.prepared();
    let mut cfg = RenderConfig::new(24, 24);
    cfg.spp = 2;
    // Pinned, not the default (two since the checksums were recorded): the
    // images are the code's at fixed settings, and only a machine of each
    // vendor can record its own.
    cfg.final_gather = 1;
    // Likewise BRDF-sampled gathers, the default before the cache's guide
    // (2026-12-06, a third session): the guide's images are checked
    // against these in expectation (`gather_guide.rs`) and are the same on
    // any thread count (`render.rs`).
    cfg.gather_directions = GatherDirections::Brdf;
    let maps = maps(tracer);
    let full = render(prepared, Some(&maps), &cfg).unwrap();
    cfg.final_gather = 0;
    let no_gather = render(prepared, Some(&maps), &cfg).unwrap();
    cfg.view = View::Map {
        primary_only: false,
    };
    let map = render(prepared, Some(&maps), &cfg).unwrap();
    cfg.view = View::DirectOnly;
    let direct = render(prepared, None, &cfg).unwrap();
    cfg.view = View::Full;
    let path = render_path(prepared, &cfg, PathPart::Full).unwrap();
    [full, no_gather, map, direct, path]
}

fn embree_tracer(name: &str, isa: Isa) -> Tracer<CommittedScene> {
    let device = Device::with_isa(isa).unwrap();
    let prepared: EmbreeScene = Scene::open(name).unwrap().commit(&device).unwrap();
    Tracer::new(prepared)
}

/// `(CPU vendor, kernel set, scene, checksums of `images`)`, as this test
/// prints them on a mismatch; recorded on an Intel Xeon with AVX-512 and
/// an AMD EPYC. AVX-512 is the same on every vendor (see `isa_pinning.rs`);
/// the narrower sets are per vendor.
///
/// [`UNRECORDED`] marks an image that changed on purpose where only another
/// vendor's machine could record it: the test prints its value there (to be
/// recorded) and checks the image's other four.
type Recorded = (Option<&'static str>, Isa, &'static str, [u64; 5]);

/// An image not yet recorded on its vendor (none is now). The AMD EPYC's
/// default renders, which changed with the irradiance cache's kernel share,
/// its sight and its walled cells while only Xeons ran the project, were
/// recorded again on an EPYC on 2026-12-06 (a fifth session).
const UNRECORDED: u64 = 0;
const RECORDED: &[Recorded] = &[
    (
        Some("AuthenticAMD"),
        Isa::Sse2,
        "cornell",
        [
            0xf6a4_bbf2_5f66_8c93, // was 0x8b67_d95c_ce2d_b630, before the kernel share
            0x9046_29c0_7be0_d2bb,
            0x288b_67aa_b7bc_2243,
            0x6f21_efa0_a969_ac15,
            0x8484_4289_4a83_19f3,
        ],
    ),
    (
        Some("AuthenticAMD"),
        Isa::Sse2,
        "cornell-glass",
        [
            0xdf6b_5449_7907_c36c, // was 0x2de4_f3e1_87c8_383d, before the kernel share
            0x188f_3cd0_93ed_c80d,
            0x22c0_07c7_c4ff_4be5,
            0x7d31_4770_115d_f392,
            0x28c6_e59b_8cd7_ed74,
        ],
    ),
    (
        Some("AuthenticAMD"),
        Isa::Avx2,
        "cornell",
        [
            0xae56_1ce7_684e_65a5, // was 0x5b15_303c_7cb8_2700, before the kernel share
            0x2b0e_e6fd_62a9_82f4,
            0x23ef_181f_734a_88b3,
            0x7bf4_13aa_e0b9_b558,
            0x5913_9f9e_5e0c_8e05,
        ],
    ),
    (
        Some("AuthenticAMD"),
        Isa::Avx2,
        "cornell-glass",
        [
            0xbd5e_4196_8b31_48c5, // was 0xa4fb_1615_d028_c581, before the kernel share
            0xced0_e949_2e66_37a0,
            0xe550_f68f_2c86_4a54,
            0xa4a7_cc85_4afe_6c5e,
            0xafd6_ee4e_f27b_1862,
        ],
    ),
    (
        Some("GenuineIntel"),
        Isa::Sse2,
        "cornell",
        [
            0x2d3b_3778_0b52_f913, // was 0xdabd_3550_0978_52a8, before the cache's sight
            0xd392_ae5f_cf25_5832,
            0xd1e8_9d4b_527f_ce9e,
            0x21a7_3131_5da6_2d84,
            0xcbfc_b34c_1f85_2343,
        ],
    ),
    (
        Some("GenuineIntel"),
        Isa::Sse2,
        "cornell-glass",
        [
            0xa96b_bc73_9f4b_a2b1, // was 0x400c_d7e1_d6e8_dd94, before the walled cells
            0xe19d_978e_0c1b_28f6,
            0xd178_adc3_505a_1a63,
            0x4422_8fbf_cd9a_27b2,
            0x8497_55c7_ad3b_1370,
        ],
    ),
    (
        Some("GenuineIntel"),
        Isa::Avx2,
        "cornell",
        [
            0xd1f0_0b18_156e_69bd, // was 0x5c5b_084e_7e6a_7644, before the cache's sight
            0x43f7_f470_ef9e_c433,
            0x8bf2_5aa2_f039_5905,
            0xddd1_6012_a5f9_002e,
            0x749b_6bbc_8104_660e,
        ],
    ),
    (
        Some("GenuineIntel"),
        Isa::Avx2,
        "cornell-glass",
        [
            0x6ee9_8703_1d08_ae75, // was 0x46d0_68e2_6c0b_a48b, before the walled cells
            0x9cfc_00b6_6ff6_7aef,
            0x1ebf_4aeb_3fdd_6fee,
            0xefdb_fecd_2b67_4307,
            0x2e69_8064_d39c_888b,
        ],
    ),
    (
        None,
        Isa::Avx512,
        "cornell",
        [
            0x0376_0c26_1309_540e, // was 0x400b_4d4e_21b3_f0bf, before the walled cells
            0xfef1_c0e4_f37c_ce91,
            0x0605_42eb_3124_8c84,
            0xb30d_e337_1801_ec7b,
            0xd099_d9ce_3f46_4ccc,
        ],
    ),
    (
        None,
        Isa::Avx512,
        "cornell-glass",
        [
            0x5d16_9ee2_1bcf_10a7, // was 0x9e0d_f930_cdfb_c314, before the walled cells
            0x133e_be17_baba_c39b,
            0xbf96_9617_d9e1_7b6d,
            0x9f14_6f8a_e7f9_9e7a,
            0x3d36_ff31_c271_aa61,
        ],
    ),
];

#[test]
fn pinned_images_have_the_recorded_checksums() {
    let vendor = cpu_vendor();
    let mut checked = 0;
    for &(who, isa, name, expected) in RECORDED {
        if !isa.is_supported() || who.is_some_and(|w| vendor.as_deref() != Some(w)) {
            continue;
        }
        let mut got = images(&embree_tracer(name, isa)).map(|i| checksum(&i));
        for (i, (g, e)) in got.iter_mut().zip(expected).enumerate() {
            if e == UNRECORDED {
                eprintln!(
                    "{} {name} on {vendor:?}: image {i} is {g:#018x}, not yet recorded",
                    isa.name()
                );
                *g = UNRECORDED;
            }
        }
        assert_eq!(
            got,
            expected,
            "{} {name} on {vendor:?}: got {:#018x?}",
            isa.name(),
            got
        );
        checked += 1;
    }
    eprintln!("{checked} recorded image sets reproduced on {vendor:?}");
}

#[test]
fn a_user_caster_renders_embrees_images() {
    let device = Device::new().unwrap();
    for name in ["cornell", "cornell-glass"] {
        let scene = Scene::open(name).unwrap();
        let own = OneByOne(scene.embree_geometry(&device).unwrap());
        let mine = Tracer::new(PreparedScene::new(scene.clone(), own).unwrap());
        let embree = Tracer::new(scene.commit(&device).unwrap());
        let (a, b) = (images(&mine), images(&embree));
        for (i, (a, b)) in a.iter().zip(&b).enumerate() {
            assert_eq!(a.pixels, b.pixels, "{name}, image {i}");
        }
    }
}
