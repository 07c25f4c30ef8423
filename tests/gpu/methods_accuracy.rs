//! Each comparison method against the ray-cast reference, on a scene where the light is small
//! next to the caster (table1-960) and one where it is large (fig1-large-light): each must behave
//! as its construction says, and the numbers are printed
//! (`cargo test --release --test gpu methods_accuracy -- --nocapture`).

use dbuffer::render::methods::{pcf, sampled};
use dbuffer::render::{Knobs, Method};

use crate::support::scored::Scored;

const SIZE: u32 = 96;

fn lights(n: u32) -> Knobs {
    Knobs::default().with(&sampled::LIGHTS, n)
}

#[test]
fn every_method_behaves_as_built() {
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    for name in ["table1-960", "fig1-large-light"] {
        let mut b = Scored::new(name, SIZE);
        let d = Knobs::default();
        let (hard, hard_m) = b.measure(Method::HARD, d);
        let (_, dbuffer) = b.measure(Method::DBUFFER, d);
        let (_, center) = b.measure(Method::DBUFFER_CENTER, d);
        let (_, pcss) = b.measure("pcss".parse::<Method>().unwrap(), d);
        let (_, pcf) = b.measure("pcf".parse::<Method>().unwrap(), d.with(&pcf::RADIUS, 4));
        let (pcf0, _) = b.measure("pcf".parse::<Method>().unwrap(), d.with(&pcf::RADIUS, 0));
        let (_, few) = b.measure("sampled".parse::<Method>().unwrap(), lights(4));
        let (_, many) = b.measure("sampled".parse::<Method>().unwrap(), lights(64));

        // A hard shadow is all or nothing, and PCF with one tap is that same test.
        assert!(hard.visibility.iter().all(|&v| v == 0.0 || v == 1.0));
        assert_eq!(
            pcf0.visibility, hard.visibility,
            "{name}: PCF r = 0 is the hard test"
        );
        // Filtering and the penumbra estimates move toward the reference...
        assert!(pcf.penumbra_mae < hard_m.penumbra_mae, "{name}: PCF");
        assert!(
            pcss.penumbra_mae < 0.5 * hard_m.penumbra_mae,
            "{name}: PCSS"
        );
        assert!(
            dbuffer.penumbra_mae < 0.5 * hard_m.penumbra_mae,
            "{name}: D-buffer"
        );
        // ...and averaging more point lights converges on the area light.
        assert!(many.penumbra_mae <= 0.03, "{name}: 64 lights {many:?}");
        assert!(
            few.penumbra_mae > many.penumbra_mae,
            "{name}: 4 vs 64 lights"
        );
        // Silhouettes from the centre alone lose boundary correctness.
        assert!(
            center.class_mismatch_pct > dbuffer.class_mismatch_pct,
            "{name}: centre {center:?} vs disk {dbuffer:?}"
        );
        if name == "fig1-large-light" {
            // The light much larger than the caster: the centre silhouette is plainly wrong.
            assert!(center.class_mismatch_pct > 2.0 * dbuffer.class_mismatch_pct);
        }
    }
}
