//! What several benchmarks share: this thread's CPU time and the pixel
//! fixtures embedded in the binary.

/// This thread's CPU time in ms (user + system): unlike the wall clock it
/// does not count the time other processes held the core, so step times
/// stay meaningful on a busy machine. `None` where not available.
#[cfg(target_os = "linux")]
pub fn thread_cpu_ms() -> Option<f64> {
    #[repr(C)]
    struct Timespec {
        sec: i64,
        nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = Timespec { sec: 0, nsec: 0 };
    // SAFETY: `t` is a valid, writable timespec for the call's duration.
    let r = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) };
    (r == 0).then(|| t.sec as f64 * 1e3 + t.nsec as f64 / 1e6)
}

#[cfg(not(target_os = "linux"))]
pub fn thread_cpu_ms() -> Option<f64> {
    None
}

/// Fixture files of the pixel cases, embedded so the bench runs from any directory.
const PIXEL_FIXTURES: [(&str, &[u8]); 9] = [
    (
        "cases.json",
        include_bytes!("../../assets/pixel/cases.json"),
    ),
    ("fish.png", include_bytes!("../../assets/pixel/fish.png")),
    (
        "fish_body_boundary.png",
        include_bytes!("../../assets/pixel/fish_body_boundary.png"),
    ),
    (
        "fish_scale.png",
        include_bytes!("../../assets/pixel/fish_scale.png"),
    ),
    (
        "fish_strokes.json",
        include_bytes!("../../assets/pixel/fish_strokes.json"),
    ),
    (
        "trunk_unpatterned.png",
        include_bytes!("../../assets/pixel/trunk_unpatterned.png"),
    ),
    (
        "trunk_boundary.png",
        include_bytes!("../../assets/pixel/trunk_boundary.png"),
    ),
    (
        "bark_scale.png",
        include_bytes!("../../assets/pixel/bark_scale.png"),
    ),
    (
        "trunk_strokes.json",
        include_bytes!("../../assets/pixel/trunk_strokes.json"),
    ),
];

pub fn fixture(name: &str) -> Result<&'static [u8], String> {
    PIXEL_FIXTURES
        .iter()
        .find(|f| f.0 == name)
        .map(|f| f.1)
        .ok_or_else(|| format!("no embedded fixture {name}"))
}
