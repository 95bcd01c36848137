//! The zoo's tests: every scene loads and passes the simulator's checks, twins have no
//! paths, the generator is deterministic and its scenes differ.

use super::*;
use crate::campaign::layout::Layout;
use crate::campaign::manifest::Campaign;
use crate::params::ParamGuard;
use crate::{scene_sections, Scene};
use geo::Coord;

#[test]
fn every_scene_loads_and_passes_the_simulators_checks() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = generate(1, 21);
    let written = write(dir.path(), &scenes).unwrap();
    assert_eq!(written.len(), 3 * scenes.len());
    for d in &written {
        let c = Campaign::load(&d.join("campaign.toml"))
            .unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        let (scene, clutter) = scene_sections(&c).unwrap();
        let layout = Layout::load(&c.layout_path()).unwrap();
        for (k, p) in c.manifest.poses.iter().enumerate() {
            assert!(
                layout.is_free(Coord { x: p.x_m, y: p.y_m }),
                "{}: pose {k} not in free space",
                d.display()
            );
        }
        for t in &scene.targets {
            assert!(layout.is_free(Coord { x: t.x_m, y: t.y_m }));
        }
        let twin = d.to_string_lossy().ends_with("-twin");
        assert_eq!(clutter.is_none(), twin, "{}", d.display());
        assert_eq!(scene.walls, !twin);
        let n = c.manifest.poses.len();
        assert!((12..=40).contains(&n), "{}: {n} poses", d.display());
        assert!([16, 100, 400].contains(&c.manifest.array.elements));
        let st = c.manifest.directions.step_deg;
        assert!((2.5..=10.0).contains(&st));
        assert!((1..=4).contains(&c.manifest.pulses));
        assert!(n * c.manifest.directions.count() * c.manifest.pulses <= SWEEP_BUDGET);
        let p = &c.manifest.processing;
        assert_eq!(
            (p.max_delay_ns, p.noise_from_ns, p.coupling),
            (80.0, 100.0, CouplingRemoval::Gate)
        );
        for w in &layout.walls {
            assert!(
                scene.materials.contains_key(&w.material),
                "{}: material {} not in [scene.materials]",
                d.display(),
                w.material
            );
        }
    }
}

#[test]
fn the_twin_simulates_noise_and_coupling_only() {
    let s = &generate(3, 7)[6];
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), std::slice::from_ref(s)).unwrap();
    let c = Campaign::load(&dir.path().join(format!("{}-twin/campaign.toml", s.name))).unwrap();
    let (cfg, clutter) = scene_sections(&c).unwrap();
    assert!(clutter.is_none() && !cfg.walls && !cfg.specular && cfg.targets.is_empty());
    let scene = Scene::build(
        Layout::load(&c.layout_path()).unwrap(),
        cfg,
        None,
        6e9,
        c.manifest.seed,
    );
    assert!(scene.scatterers.is_empty() && scene.clusters.is_empty());
    for p in &c.manifest.poses {
        assert!(scene.paths(Coord { x: p.x_m, y: p.y_m }).is_empty());
    }
    // the scene itself has paths
    let full = Campaign::load(&dir.path().join(format!("{}/campaign.toml", s.name))).unwrap();
    let (cfg, clutter) = scene_sections(&full).unwrap();
    let scene = Scene::build(
        Layout::load(&full.layout_path()).unwrap(),
        cfg,
        clutter.as_ref(),
        6e9,
        full.manifest.seed,
    );
    let p = full.manifest.poses[0];
    assert!(!scene.paths(Coord { x: p.x_m, y: p.y_m }).is_empty());
}

#[test]
fn the_generator_is_deterministic_and_its_scenes_differ() {
    let a = generate(1, 21);
    assert_eq!(a, generate(1, 21));
    // a prefix of a larger zoo
    assert_eq!(a[..10], generate(1, 10)[..]);
    let b = generate(2, 21);
    assert!(a.iter().zip(&b).all(|(x, y)| x.manifest != y.manifest));
    let names: std::collections::BTreeSet<&str> = a.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names.len(), a.len());
    // every layout and manifest distinct; sizes, materials, N and families spread
    for (i, x) in a.iter().enumerate() {
        for y in &a[i + 1..] {
            assert_ne!(x.layout, y.layout);
            assert_ne!(x.extent_m(), y.extent_m());
        }
    }
    let mats: std::collections::BTreeSet<&str> = a.iter().map(|s| s.perimeter_material()).collect();
    assert_eq!(mats.len(), 5);
    let ns: std::collections::BTreeSet<usize> = a.iter().map(|s| s.elements()).collect();
    assert_eq!(ns.len(), 3);
    let fams: std::collections::BTreeSet<&str> = a.iter().map(|s| s.family.name()).collect();
    assert_eq!(fams.len(), 7);
    let longest = a.iter().map(|s| s.extent_m().0.max(s.extent_m().1));
    assert!(longest.clone().fold(0.0, f64::max) > 40.0);
    assert!(longest.fold(f64::MAX, f64::min) < 12.5);
    // realisations differ in the seed only
    let r = a[0].realisation(2);
    assert_ne!(r.seed(), a[0].seed());
    assert_eq!(r.layout, a[0].layout);
    assert_eq!(a[0].realisation(1), a[0]);
    // the twin keeps the campaign (poses, array, steps)
    let t = a[0].twin();
    assert_eq!(t.sweeps(), a[0].sweeps());
    assert!(!t.manifest.contains("[clutter"));
}

#[test]
fn materials_are_itu_values_at_60_ghz() {
    let m = materials();
    let tan = |n: &str| m[n].loss_tangent;
    assert!(
        (tan("concrete") - 0.0506).abs() < 2e-3,
        "{}",
        tan("concrete")
    );
    assert!((tan("plasterboard") - 0.0214).abs() < 2e-3);
    assert!((tan("glass") - 0.0271).abs() < 2e-3);
    assert!((tan("wood") - 0.057).abs() < 2e-3);
    assert!(m["metal"].gamma().norm() > 0.999);
    // and the scene's sections take them
    let s = &generate(5, 1)[0];
    let t: toml::Table = toml::from_str(&s.manifest).unwrap();
    let cfg: SceneConfig = t["scene"].clone().try_into().unwrap();
    assert_eq!(cfg.materials, m);
    cfg.check().unwrap();
}
