//! `flaneur serve` serves what it was told to serve and nothing else: a symbolic link
//! put in a served file's place after the start serves nothing outside, and a served
//! folder gives its regular files, no link followed, no hidden file, no `..`.

mod common;

use std::io::{BufRead, Read, Write};
use std::net::TcpStream;
use std::os::unix::fs::symlink;
use std::path::Path;
use std::process::{Child, Command, Stdio};

use flaneur::{BuildOptions, Database};

/// A server process, killed when dropped.
struct Server {
    child: Child,
    /// `http://127.0.0.1:PORT`.
    base: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `flaneur serve ARGS` on a free loopback port, once it listens: its URL's base taken
/// from the first database it says it serves.
fn serve(args: &[&Path]) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .arg("serve")
        .args(args)
        .args(["--port", "0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
    let url = lines
        .by_ref()
        .map(|l| l.unwrap())
        .find_map(|l| {
            Some(
                l.strip_prefix("serving ")?
                    .split_whitespace()
                    .next()?
                    .to_string(),
            )
        })
        .expect("the server names what it serves");
    std::thread::spawn(move || lines.for_each(drop));
    let base = url[..url["http://".len()..].find('/').unwrap() + "http://".len()].to_string();
    Server { child, base }
}

/// A plain GET of `path` on `base` as sent (no client normalising it): the status and body.
fn get(base: &str, path: &str) -> (u16, Vec<u8>) {
    let mut tcp = TcpStream::connect(base.strip_prefix("http://").unwrap()).unwrap();
    write!(
        tcp,
        "GET {path} HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut answer = Vec::new();
    tcp.read_to_end(&mut answer).unwrap();
    let split = answer
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("an HTTP answer");
    let head = String::from_utf8_lossy(&answer[..split]).to_string();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (status, answer[split + 4..].to_vec())
}

/// A secret outside every served folder.
fn secret() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("secret.txt");
    std::fs::write(&path, b"the secret outside the served files").unwrap();
    (dir, path)
}

fn small_city(seed: u64) -> common::City {
    common::city(
        40,
        seed,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

#[test]
fn a_link_swapped_in_after_the_start_serves_nothing_outside() {
    let c = small_city(1);
    let (_outside, secret) = secret();
    let server = serve(&[&c.db]);
    let (status, body) = get(&server.base, "/city.flaneur");
    assert_eq!(
        (status, body.len() as u64),
        (200, std::fs::metadata(&c.db).unwrap().len())
    );
    // The served database replaced by a link to a file outside.
    std::fs::remove_file(&c.db).unwrap();
    symlink(&secret, &c.db).unwrap();
    let (status, body) = get(&server.base, "/city.flaneur");
    assert!(
        !String::from_utf8_lossy(&body).contains("secret"),
        "served the link's target ({status})"
    );
    assert_eq!(status, 404);
    // A new build renamed over the link is a regular file again: served.
    let other = small_city(2);
    std::fs::copy(&other.db, c.dir.path().join("staged")).unwrap();
    std::fs::rename(c.dir.path().join("staged"), &c.db).unwrap();
    let (status, body) = get(&server.base, "/city.flaneur");
    assert_eq!((status, body), (200, std::fs::read(&other.db).unwrap()));
}

#[test]
fn a_served_folder_gives_its_regular_files_and_nothing_else() {
    let c = small_city(3);
    let (outside, secret) = secret();
    let site = c.dir.path();
    std::fs::write(site.join("tileset.json"), br#"{"asset":{"version":"1.1"}}"#).unwrap();
    std::fs::create_dir(site.join("tiles")).unwrap();
    std::fs::write(site.join("tiles/0.glb"), b"glTF tile").unwrap();
    std::fs::write(site.join(".env"), b"TOKEN=hidden").unwrap();
    symlink(&secret, site.join("link.txt")).unwrap();
    symlink(outside.path(), site.join("elsewhere")).unwrap();
    let server = serve(&[site]);

    assert_eq!(get(&server.base, "/tileset.json").0, 200);
    assert_eq!(
        get(&server.base, "/tiles/0.glb"),
        (200, b"glTF tile".to_vec())
    );
    for path in [
        "/link.txt",
        "/elsewhere/secret.txt",
        "/../secret.txt",
        "/tiles/../../secret.txt",
        "/%2e%2e/secret.txt",
        "/.env",
        "/tiles",
        "/",
        "/missing.flaneur",
    ] {
        let (status, body) = get(&server.base, path);
        let body = String::from_utf8_lossy(&body);
        assert!(
            !body.contains("secret") && !body.contains("TOKEN"),
            "{path}: {status} {body}"
        );
        assert!(status == 404 || status == 400, "{path}: {status}");
    }

    // The database in it reads over HTTP, by ranges with its ETag pinned, as the file.
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url(&format!("{}/city.flaneur", server.base)).unwrap();
    let all = local.bounds();
    let (a, b) = (local.range(&all).unwrap(), remote.range(&all).unwrap());
    assert_eq!((a.ids(), &a.pages), (b.ids(), &b.pages));
    for o in &a.objects {
        assert_eq!(local.mesh(o).unwrap(), remote.mesh(o).unwrap());
    }
    assert!(remote.remote_warnings().is_empty());
}

#[test]
fn a_folder_among_files_is_refused() {
    let c = small_city(4);
    let out = common::flaneur(&[
        "serve",
        c.db.to_str().unwrap(),
        c.dir.path().to_str().unwrap(),
        "--port",
        "0",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("one folder"), "{err}");
}
