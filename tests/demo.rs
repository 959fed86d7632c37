//! `flaneur demo` on a small city, headless: it walks, draws its flight, and ends with where
//! its database is and what to try next, having said once what its figures mean.

mod common;

#[test]
fn the_demo_ends_with_its_database_and_the_next_steps() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(["demo", "--objects", "150", "--frames", "30", "--cache"])
        .arg(&cache)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let text = common::succeeded(&out);
    let db = cache.join("demo-150.flaneur");
    assert!(db.is_file(), "the demo kept its database:\n{text}");

    // Its own words, explained once, before the walks that use them.
    assert_eq!(text.matches("SF: the scale factor").count(), 1, "{text}");
    assert!(text.contains("Visual misses: objects in view"), "{text}");
    assert!(text.contains("PM + DAG: "), "{text}");
    assert!(
        text.contains("REVIEW (the thesis's 'optimal' configuration"),
        "{text}"
    );
    assert!(!text.lines().any(|l| l == "optimal:"), "{text}");

    // The last word: where the database is and what to run on it.
    let tail = &text[text.rfind("the city's database is").expect(&text)..];
    let shown = db.display().to_string();
    for next in [
        format!("flaneur view {shown}"),
        format!("flaneur info {shown}"),
        format!("flaneur serve {shown} --port 8080"),
        "flaneur walk http://127.0.0.1:8080/demo-150.flaneur --never-wait".to_string(),
    ] {
        assert!(
            tail.contains(&next),
            "the demo ends without {next:?}:\n{tail}"
        );
    }
}
