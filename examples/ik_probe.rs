use nalgebra::Vector3;
use robokrige::kinematics::{self, IkOptions, IkTarget};
fn main() {
    let r = kinematics::preset("scara-rh3frh5515").unwrap();
    let d = robokrige::dataset::read_csv(std::path::Path::new("/tmp/v.csv")).unwrap();
    for q in d.q.iter().take(5) {
        let mut t = r.fk(q).unwrap();
        t.translation.vector += Vector3::new(0.03, -0.02, 0.01);
        println!(
            "{q:?} -> {:?}",
            r.ik(&IkTarget::pose(&t), q, &IkOptions::default())
        );
    }
}
