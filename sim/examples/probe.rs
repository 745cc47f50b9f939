use robot::hardware::*;
use sim::config::*;
fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let world = WorldDescription::parse("name='r'\n[start]\nx=0\ny=0\n[[wall]]\npoints=[[-10,-10],[10,-10],[10,10],[-10,10]]\nclosed=true\n", "r.toml").unwrap();
    let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let g = robot.geometry();
    let twin = sim::Twin::new(&world, &robot, &NoiseSettings::NONE, 1).unwrap();
    let mut r = sim::SimRobot::new(twin, 9600);
    r.advance(g.tenths_for_distance(1.0).unwrap()).unwrap();
    r.wait_drive(DriveWait::motors(60000)).unwrap();
    let s = r.drive_status().unwrap();
    println!("after advance {:?} truth {:?}", s, r.twin().true_pose());
    for _ in 0..50 {
        r.twin_mut().step();
    }
    println!(
        "after coast truth {:?} edges {:?}",
        r.twin().true_pose(),
        r.twin().encoder_edges()
    );
    let th0 = r.twin().true_pose().theta;
    let e0 = r.twin().encoder_edges();
    r.turn_left(280).unwrap();
    for k in 0..700 {
        r.twin_mut().step();
        let e = r.twin().encoder_edges();
        let (dl, dr) = ((e.0 - e0.0) as f64, (e.1 - e0.1) as f64);
        let expected = (dl + dr) * g.metres_per_count() / g.track_m;
        let truth = r.twin().true_pose().theta - th0;
        if k % 25 == 0 {
            println!(
                "{k:4} edges {dl:6} {dr:6} expected {expected:.5} truth {truth:.5} diff {:.6}  on {:?}",
                truth - expected,
                r.twin().firmware().motors_on()
            );
        }
    }
}
