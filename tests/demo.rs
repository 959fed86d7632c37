//! `flaneur demo` on a small city, headless: it walks, compares the four modes in one
//! table, draws its flight, and ends with where its database is and what to try next,
//! having said once what its figures mean.

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

    // The four modes side by side in one table, each with its figures, drawn against
    // full detail where the machine has a GPU adapter (lavapipe at least, here).
    let table = &text[text.find("walking the four modes").expect(&text)..];
    let header = table.lines().nth(1).unwrap();
    for column in ["over 50 ms", "pages", "visual misses", "triangles/frame", "PSNR dB"] {
        assert!(header.contains(column), "{header}");
    }
    for mode in ["REVIEW ", "BOX ", "PVS ", "VISUAL (η 0.001) "] {
        let row = table
            .lines()
            .find(|l| l.trim_start().starts_with(mode))
            .unwrap_or_else(|| panic!("no {mode} row:\n{table}"));
        let figures: Vec<&str> = row[row.find(mode).unwrap() + mode.len()..]
            .split_whitespace()
            .collect();
        assert_eq!(figures.len(), 6, "{row}");
        assert_eq!(figures[0], "30", "{row}");
        let psnr: f64 = figures[5].parse().unwrap_or_else(|_| panic!("{row}"));
        assert!((20.0..=60.0).contains(&psnr), "{row}");
        let pages: u64 = figures[2].parse().unwrap();
        assert!(pages > 0, "{row}");
    }

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
