//! HTTP servers for the network tests, on loopback only: nginx from the distribution's
//! packages (`.ci/run` installs it), started on a free port over a folder and stopped
//! when dropped; and a misbehaving server of our own on real TCP, for the answers no
//! well-kept server gives (cut bodies, extra bytes, wrong ranges).
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::Duration;

/// Client options quick to give up: the failure tests need not wait for the default
/// backoff.
pub fn impatient() -> flaneur::store::HttpOptions {
    flaneur::store::HttpOptions {
        retries: 2,
        backoff: Duration::from_millis(10),
        timeout: Duration::from_secs(5),
        ..flaneur::store::HttpOptions::default()
    }
}

/// nginx serving `root` on 127.0.0.1 (`flaneur_bench::nginx`, which the crowd bench
/// starts too), a test's failure when it cannot start.
pub struct Nginx(flaneur_bench::nginx::Nginx);

pub use flaneur_bench::nginx::NginxConfig;

impl Nginx {
    pub fn start(root: &Path) -> Nginx {
        Nginx::start_with(root, NginxConfig::default())
    }

    pub fn start_with(root: &Path, config: NginxConfig) -> Nginx {
        Nginx(
            flaneur_bench::nginx::Nginx::start(root, config).unwrap_or_else(|e| {
                panic!("{e}: the network tests need it (.ci/run installs nginx-light)")
            }),
        )
    }

    /// The URL of `name` in the served folder.
    pub fn url(&self, name: &str) -> String {
        self.0.url(name)
    }

    /// Stops the server now (a server gone mid-walk).
    pub fn stop(&mut self) {
        self.0.stop()
    }
}

/// What the misbehaving server does wrong, after it has answered `honest` requests well
/// (a database's open is two).
#[derive(Clone, Copy, Debug)]
pub enum Fault {
    /// Says Content-Length of the range, sends half of it, closes the connection.
    CutBody,
    /// Sends the range and then as many bytes again (Content-Length says so).
    LongBody,
    /// Says and sends fewer bytes than asked, with a Content-Range that matches them.
    ShortRange,
    /// Answers with this status and an empty body.
    Status(u16),
    /// Flips one byte of every body.
    Garble,
    /// Reads the request and resets the connection (a TCP RST, no answer): a server
    /// that lets the open through and then refuses everything.
    Reset,
    /// Answers this many requests with 503 and an empty body, then well again (a server
    /// that was away for a while).
    Outage(usize),
    /// Sends the right bytes but neither an ETag nor a Last-Modified, on every answer (the
    /// honest ones too): a server that names no version of the file.
    NoValidators,
    /// Sends the range gzip-compressed (`gzip -n`), saying so in Content-Encoding and
    /// Content-Length, though the client asked for no encoding.
    Gzip,
}

/// A server of our own on real TCP, serving `bytes` as one file at any path, honest for
/// its first `honest` requests and then `fault` on every one (an outage's, on as many as
/// it lasts).
pub struct Misbehaving {
    port: u16,
    stop: Arc<AtomicBool>,
    /// Requests answered so far.
    pub requests: Arc<AtomicUsize>,
}

impl Misbehaving {
    pub fn start(bytes: Vec<u8>, honest: usize, fault: Fault) -> Misbehaving {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        listener.set_nonblocking(true).unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let requests = Arc::new(AtomicUsize::new(0));
        let bytes = Arc::new(bytes);
        {
            let (stop, requests) = (stop.clone(), requests.clone());
            thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    match listener.accept() {
                        Ok((stream, _)) => {
                            let (bytes, requests) = (bytes.clone(), requests.clone());
                            thread::spawn(move || serve(stream, &bytes, honest, fault, &requests));
                        }
                        Err(_) => thread::sleep(Duration::from_millis(5)),
                    }
                }
            });
        }
        Misbehaving {
            port,
            stop,
            requests,
        }
    }

    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/city.flaneur", self.port)
    }
}

impl Drop for Misbehaving {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// Answers requests on one connection until it closes.
fn serve(stream: TcpStream, file: &[u8], honest: usize, fault: Fault, requests: &AtomicUsize) {
    stream.set_nonblocking(false).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut reader = BufReader::new(stream.try_clone().unwrap());
    let mut out = stream;
    loop {
        let mut range = None;
        let mut line = String::new();
        if reader.read_line(&mut line).unwrap_or(0) == 0 {
            return;
        }
        loop {
            let mut h = String::new();
            if reader.read_line(&mut h).unwrap_or(0) == 0 {
                return;
            }
            if h == "\r\n" {
                break;
            }
            if let Some(v) = h.to_ascii_lowercase().strip_prefix("range: bytes=") {
                let (a, b) = v.trim().split_once('-').unwrap();
                range = Some(match (a.parse::<usize>(), b.parse::<usize>()) {
                    (Ok(a), Ok(b)) => (a, b.min(file.len() - 1)),
                    // A suffix: the last b bytes.
                    (Err(_), Ok(b)) => (file.len().saturating_sub(b), file.len() - 1),
                    _ => panic!("a range the client should not send: {h}"),
                });
            }
        }
        let n = requests.fetch_add(1, Ordering::Relaxed);
        let (a, b) = range.unwrap_or((0, file.len() - 1));
        let mut body = file[a..=b].to_vec();
        let total = file.len();
        let etag = if matches!(fault, Fault::NoValidators) {
            ""
        } else {
            "ETag: \"v1\"\r\n"
        };
        let head = |len: usize, a: usize, b: usize| {
            format!(
                "HTTP/1.1 206 Partial Content\r\nContent-Length: {len}\r\nContent-Range: bytes {a}-{b}/{total}\r\n{etag}\r\n"
            )
        };
        let back = matches!(fault, Fault::Outage(away) if n >= honest + away);
        if n < honest || back {
            let _ = out.write_all(head(body.len(), a, b).as_bytes());
            let _ = out.write_all(&body);
            continue;
        }
        match fault {
            Fault::CutBody => {
                let _ = out.write_all(head(body.len(), a, b).as_bytes());
                let _ = out.write_all(&body[..body.len() / 2]);
                return;
            }
            Fault::Reset => {
                reset(&out);
                return;
            }
            Fault::LongBody => {
                let len = body.len();
                let _ = out.write_all(head(2 * len, a, b).as_bytes());
                let _ = out.write_all(&body);
                let _ = out.write_all(&body);
            }
            Fault::ShortRange => {
                let cut = (body.len() / 2).max(1);
                let _ = out.write_all(head(cut, a, a + cut - 1).as_bytes());
                let _ = out.write_all(&body[..cut]);
            }
            Fault::Outage(_) => {
                let _ = out.write_all(b"HTTP/1.1 503 Away\r\nContent-Length: 0\r\n\r\n");
            }
            Fault::Status(code) => {
                let _ = out.write_all(
                    format!("HTTP/1.1 {code} Oops\r\nContent-Length: 0\r\n\r\n").as_bytes(),
                );
            }
            Fault::NoValidators => {
                let _ = out.write_all(head(body.len(), a, b).as_bytes());
                let _ = out.write_all(&body);
            }
            Fault::Gzip => {
                let packed = gzip(&body);
                let head = head(packed.len(), a, b);
                let head = head.replace("\r\n\r\n", "\r\nContent-Encoding: gzip\r\n\r\n");
                let _ = out.write_all(head.as_bytes());
                let _ = out.write_all(&packed);
            }
            Fault::Garble => {
                let mid = body.len() / 2;
                body[mid] ^= 0x5a;
                let _ = out.write_all(head(body.len(), a, b).as_bytes());
                let _ = out.write_all(&body);
            }
        }
        let _ = out.flush();
        let _ = reader.get_mut().read(&mut []);
    }
}

/// `bytes` compressed by the system's gzip.
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut child = std::process::Command::new("gzip")
        .args(["-c", "-n"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("gzip (a Debian essential package)");
    let mut stdin = child.stdin.take().unwrap();
    let input = bytes.to_vec();
    let feeder = thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    feeder.join().unwrap().unwrap();
    assert!(out.status.success());
    out.stdout
}

/// Closes `stream` with a reset rather than a FIN: a linger of 0 seconds, which the
/// standard library does not set.
fn reset(stream: &TcpStream) {
    use std::os::fd::AsRawFd;
    let linger = libc::linger {
        l_onoff: 1,
        l_linger: 0,
    };
    // SAFETY: the descriptor is open for the call, and the option is a `linger` of
    // the length given.
    unsafe {
        libc::setsockopt(
            stream.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_LINGER,
            (&linger as *const libc::linger).cast(),
            std::mem::size_of::<libc::linger>() as libc::socklen_t,
        );
    }
}
