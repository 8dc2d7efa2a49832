//! The kernel edge of [`crate::v4l2`] (cargo feature `v4l2`, 64-bit Linux): a V4L2 capture
//! device through its ioctls, memory-mapped streaming with four buffers.
//!
//! The structures are byte buffers at the offsets and sizes of `linux/videodev2.h` on 64-bit
//! Linux (checked against the header with a C program when this was written: `v4l2_capability`
//! 104 bytes, `v4l2_fmtdesc` 64, `v4l2_frmsizeenum` 44, `v4l2_format` 208, `v4l2_requestbuffers`
//! 20, `v4l2_buffer` 88), so no bindings generator (and no libclang) is needed.
//!
//! **Not verified on a camera**: no video device exists on the machines this was built on. The
//! offsets and request numbers are checked; the call sequence follows the V4L2 capture example.

use std::ffi::CString;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::Path;
use std::time::Duration;

use crate::error::CameraError;
use crate::v4l2::{Device, DeviceFormat, FormatOffer};

const VIDIOC_QUERYCAP: u64 = 0x8068_5600;
const VIDIOC_ENUM_FMT: u64 = 0xc040_5602;
const VIDIOC_ENUM_FRAMESIZES: u64 = 0xc02c_564a;
const VIDIOC_S_FMT: u64 = 0xc0d0_5605;
const VIDIOC_REQBUFS: u64 = 0xc014_5608;
const VIDIOC_QUERYBUF: u64 = 0xc058_5609;
const VIDIOC_QBUF: u64 = 0xc058_560f;
const VIDIOC_DQBUF: u64 = 0xc058_5611;
const VIDIOC_STREAMON: u64 = 0x4004_5612;
const VIDIOC_STREAMOFF: u64 = 0x4004_5613;

const BUF_TYPE_VIDEO_CAPTURE: u32 = 1;
const MEMORY_MMAP: u32 = 1;
const CAP_VIDEO_CAPTURE: u32 = 0x0000_0001;
const CAP_STREAMING: u32 = 0x0400_0000;
const CAP_DEVICE_CAPS: u32 = 0x8000_0000;
const FRMSIZE_TYPE_DISCRETE: u32 = 1;
const BUFFERS: u32 = 4;

fn get(buf: &[u8], at: usize) -> u32 {
    u32::from_ne_bytes([buf[at], buf[at + 1], buf[at + 2], buf[at + 3]])
}

fn put(buf: &mut [u8], at: usize, v: u32) {
    buf[at..at + 4].copy_from_slice(&v.to_ne_bytes());
}

/// The largest size a `v4l2_frmsizeenum` describes: the discrete size, or a range's maximum.
fn frame_size(buf: &[u8; 44]) -> (u32, u32) {
    if get(buf, 8) == FRMSIZE_TYPE_DISCRETE {
        (get(buf, 12), get(buf, 16))
    } else {
        (get(buf, 16), get(buf, 28))
    }
}

/// A capture device, open.
struct LinuxDevice {
    path: String,
    fd: OwnedFd,
    /// The mapped buffers: address and length.
    maps: Vec<(*mut libc::c_void, usize)>,
}

// The mapped buffers are owned by this value alone and only touched through `&mut self`.
unsafe impl Send for LinuxDevice {}

impl LinuxDevice {
    fn ioctl<const N: usize>(&self, request: u64, arg: &mut [u8; N]) -> io::Result<()> {
        loop {
            // SAFETY: `arg` is a buffer of the size the request encodes (checked against the
            // header), valid for the call.
            let r = unsafe { libc::ioctl(self.fd.as_raw_fd(), request as _, arg.as_mut_ptr()) };
            if r != -1 {
                return Ok(());
            }
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
    }

    fn stop(&mut self) {
        let mut kind = [0u8; 4];
        put(&mut kind, 0, BUF_TYPE_VIDEO_CAPTURE);
        if !self.maps.is_empty() {
            let _ = self.ioctl(VIDIOC_STREAMOFF, &mut kind);
        }
        for (addr, len) in self.maps.drain(..) {
            // SAFETY: mapped by `set_format` with this length, unmapped once.
            unsafe { libc::munmap(addr, len) };
        }
        let mut req = [0u8; 20];
        put(&mut req, 4, BUF_TYPE_VIDEO_CAPTURE);
        put(&mut req, 8, MEMORY_MMAP);
        let _ = self.ioctl(VIDIOC_REQBUFS, &mut req);
    }
}

impl Drop for LinuxDevice {
    fn drop(&mut self) {
        self.stop();
    }
}

impl Device for LinuxDevice {
    fn path(&self) -> &str {
        &self.path
    }

    fn offers(&mut self) -> io::Result<Vec<FormatOffer>> {
        let mut offers = Vec::new();
        for index in 0..64 {
            let mut desc = [0u8; 64];
            put(&mut desc, 0, index);
            put(&mut desc, 4, BUF_TYPE_VIDEO_CAPTURE);
            if self.ioctl(VIDIOC_ENUM_FMT, &mut desc).is_err() {
                break;
            }
            let fourcc = get(&desc, 44);
            for size in 0..256 {
                let mut fs = [0u8; 44];
                put(&mut fs, 0, size);
                put(&mut fs, 4, fourcc);
                if self.ioctl(VIDIOC_ENUM_FRAMESIZES, &mut fs).is_err() {
                    break;
                }
                let (width, height) = frame_size(&fs);
                offers.push(FormatOffer { fourcc: fourcc.to_le_bytes(), width, height });
                if get(&fs, 8) != FRMSIZE_TYPE_DISCRETE {
                    break;
                }
            }
        }
        Ok(offers)
    }

    fn set_format(&mut self, offer: FormatOffer) -> io::Result<DeviceFormat> {
        self.stop();
        let mut fmt = [0u8; 208];
        put(&mut fmt, 0, BUF_TYPE_VIDEO_CAPTURE);
        put(&mut fmt, 8, offer.width);
        put(&mut fmt, 12, offer.height);
        put(&mut fmt, 16, u32::from_le_bytes(offer.fourcc));
        self.ioctl(VIDIOC_S_FMT, &mut fmt)?;
        let set = DeviceFormat {
            offer: FormatOffer { fourcc: get(&fmt, 16).to_le_bytes(), width: get(&fmt, 8), height: get(&fmt, 12) },
            stride: get(&fmt, 24),
        };
        let mut req = [0u8; 20];
        put(&mut req, 0, BUFFERS);
        put(&mut req, 4, BUF_TYPE_VIDEO_CAPTURE);
        put(&mut req, 8, MEMORY_MMAP);
        self.ioctl(VIDIOC_REQBUFS, &mut req)?;
        for index in 0..get(&req, 0) {
            let mut buf = [0u8; 88];
            put(&mut buf, 0, index);
            put(&mut buf, 4, BUF_TYPE_VIDEO_CAPTURE);
            put(&mut buf, 60, MEMORY_MMAP);
            self.ioctl(VIDIOC_QUERYBUF, &mut buf)?;
            let (offset, len) = (get(&buf, 64), get(&buf, 72) as usize);
            // SAFETY: a shared read/write mapping of the driver's buffer, unmapped in `stop`.
            let addr = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    len,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_SHARED,
                    self.fd.as_raw_fd(),
                    libc::off_t::from(offset),
                )
            };
            if addr == libc::MAP_FAILED {
                return Err(io::Error::last_os_error());
            }
            self.maps.push((addr, len));
            self.ioctl(VIDIOC_QBUF, &mut buf)?;
        }
        let mut kind = [0u8; 4];
        put(&mut kind, 0, BUF_TYPE_VIDEO_CAPTURE);
        self.ioctl(VIDIOC_STREAMON, &mut kind)?;
        Ok(set)
    }

    fn capture(&mut self, timeout: Duration) -> io::Result<Option<Vec<u8>>> {
        let mut poll = libc::pollfd { fd: self.fd.as_raw_fd(), events: libc::POLLIN, revents: 0 };
        let ms = libc::c_int::try_from(timeout.as_millis()).unwrap_or(libc::c_int::MAX);
        // SAFETY: one valid pollfd.
        let ready = unsafe { libc::poll(&mut poll, 1, ms) };
        match ready {
            -1 => return Err(io::Error::last_os_error()),
            0 => return Ok(None),
            _ => {}
        }
        let mut buf = [0u8; 88];
        put(&mut buf, 4, BUF_TYPE_VIDEO_CAPTURE);
        put(&mut buf, 60, MEMORY_MMAP);
        self.ioctl(VIDIOC_DQBUF, &mut buf)?;
        let index = get(&buf, 0) as usize;
        let &(addr, len) =
            self.maps.get(index).ok_or_else(|| io::Error::other("the device returned an unknown buffer"))?;
        let used = (get(&buf, 8) as usize).min(len);
        // SAFETY: the mapping is `len` bytes long and the device has filled `used` of them.
        let bytes = unsafe { std::slice::from_raw_parts(addr.cast::<u8>(), used) }.to_vec();
        self.ioctl(VIDIOC_QBUF, &mut buf)?;
        Ok(Some(bytes))
    }
}

/// Opens the V4L2 device node `path` and checks it captures video by streaming.
///
/// # Errors
/// [`CameraError::NoDevice`] for a path that names nothing; [`CameraError::DeviceOpen`] with
/// the operating system's words, or when the device cannot capture video by streaming.
pub fn open(path: &Path) -> Result<Box<dyn Device>, CameraError> {
    let device = path.display().to_string();
    let refuse = |reason: String| CameraError::DeviceOpen { device: device.clone(), reason };
    let c = CString::new(path.as_os_str().as_encoded_bytes()).map_err(|_| refuse("the path holds a NUL".into()))?;
    // SAFETY: a valid C string; the descriptor is owned at once.
    let fd = unsafe { libc::open(c.as_ptr(), libc::O_RDWR | libc::O_NONBLOCK | libc::O_CLOEXEC) };
    if fd < 0 {
        let e = io::Error::last_os_error();
        if e.kind() == io::ErrorKind::NotFound {
            return Err(CameraError::NoDevice { device });
        }
        return Err(refuse(e.to_string()));
    }
    // SAFETY: `fd` was just opened and is owned by nothing else.
    let dev = LinuxDevice { path: device.clone(), fd: unsafe { OwnedFd::from_raw_fd(fd) }, maps: Vec::new() };
    let mut cap = [0u8; 104];
    dev.ioctl(VIDIOC_QUERYCAP, &mut cap).map_err(|e| refuse(format!("not a V4L2 device ({e})")))?;
    let caps = if get(&cap, 84) & CAP_DEVICE_CAPS != 0 { get(&cap, 88) } else { get(&cap, 84) };
    if caps & CAP_VIDEO_CAPTURE == 0 || caps & CAP_STREAMING == 0 {
        return Err(refuse("it cannot capture video by streaming (a metadata node? try the next /dev/video)".into()));
    }
    Ok(Box::new(dev))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_sizes_read_discrete_and_stepwise_entries() {
        let mut fs = [0u8; 44];
        put(&mut fs, 8, FRMSIZE_TYPE_DISCRETE);
        put(&mut fs, 12, 1280);
        put(&mut fs, 16, 960);
        assert_eq!(frame_size(&fs), (1280, 960));
        put(&mut fs, 8, 3); // stepwise: min_w 12, max_w 16, step 20, min_h 24, max_h 28
        put(&mut fs, 16, 2592);
        put(&mut fs, 28, 1944);
        assert_eq!(frame_size(&fs), (2592, 1944));
    }

    #[test]
    fn a_missing_device_and_a_file_that_is_no_device_are_refused() {
        let Err(e) = open(Path::new("/dev/video-none")) else { panic!("opened a missing device") };
        assert_eq!(e, CameraError::NoDevice { device: "/dev/video-none".into() });
        let Err(e) = open(Path::new("/dev/null")) else { panic!("/dev/null is no camera") };
        assert!(e.to_string().contains("not a V4L2 device"), "{e}");
    }
}
