//! The device's descriptors as the host reads them (USB 2.0 chapter 9, CDC 1.1 §5): one
//! device, one configuration with a CDC ACM communication interface (its notification
//! endpoint) and a data interface (bulk OUT and IN), device class 0x02 with no interface
//! association descriptor: byte for byte what usb-device's builder and usbd-serial's
//! `CdcAcmClass` wrote for ddastep before (Linux's cdc-acm and Windows' usbser bind to it).

/// Endpoint 0's packet size (bMaxPacketSize0).
pub const EP0_LEN: usize = 64;
/// The bulk endpoints' packet size (full speed's largest, USB 2.0 §5.8.3).
pub const BULK_LEN: usize = 64;
/// The notification endpoint's packet size (a SERIAL_STATE is 10 bytes; never sent).
pub const NOTIFY_LEN: usize = 8;
/// Endpoint addresses: notification IN, bulk OUT, bulk IN.
pub const NOTIFY_EP: u8 = 0x81;
pub const BULK_OUT_EP: u8 = 0x02;
pub const BULK_IN_EP: u8 = 0x82;

/// obdev's shared VID/PID for CDC ACM devices (V-USB `USB-IDs-for-free.txt`: told apart by
/// their manufacturer and product strings).
const VID: u16 = 0x16c0;
const PID: u16 = 0x27dd;

const fn lo(v: u16) -> u8 {
    v.to_le_bytes()[0]
}

const fn hi(v: u16) -> u8 {
    v.to_le_bytes()[1]
}

/// The device descriptor (USB 2.0 Table 9-8).
pub static DEVICE: [u8; 18] = [
    18, 1, // bLength, DEVICE
    0x00, 0x02, // bcdUSB 2.00 (2.01 and later make Linux read a BOS descriptor)
    0x02, 0x00, 0x00, // CDC at the device level, no IAD
    EP0_LEN as u8,
    lo(VID), hi(VID), lo(PID), hi(PID),
    0x10, 0x00, // bcdDevice 0.10
    1, 2, 0, // iManufacturer, iProduct, no serial number
    1, // bNumConfigurations
];

/// The configuration descriptor and everything under it (wTotalLength bytes).
pub static CONFIG: [u8; 67] = [
    // Configuration (Table 9-10): 67 bytes, 2 interfaces, value 1, bus powered, 100 mA.
    9, 2, 67, 0, 2, 1, 0, 0x80, 50,
    // Interface 0: communication class, ACM subclass, no protocol, one endpoint.
    9, 4, 0, 0, 1, 0x02, 0x02, 0x00, 0,
    // Header functional descriptor: CDC 1.10 (CDC 1.1 §5.2.3.1).
    5, 0x24, 0x00, 0x10, 0x01,
    // ACM, bmCapabilities 0 (PSTN 1.2 §5.3.2; as usbd-serial: Linux and Windows send the line
    // requests regardless).
    4, 0x24, 0x02, 0x00,
    // Union: master interface 0, slave interface 1 (§5.2.3.8).
    5, 0x24, 0x06, 0, 1,
    // Call management: no call management, data interface 1 (§5.2.3.2).
    5, 0x24, 0x01, 0x00, 1,
    // Notification endpoint: interrupt IN, 8 bytes, every 255 ms.
    7, 5, NOTIFY_EP, 0x03, NOTIFY_LEN as u8, 0, 255,
    // Interface 1: data class, two endpoints.
    9, 4, 1, 0, 2, 0x0A, 0x00, 0x00, 0,
    // Bulk IN and bulk OUT, 64 bytes.
    7, 5, BULK_IN_EP, 0x02, BULK_LEN as u8, 0, 0,
    7, 5, BULK_OUT_EP, 0x02, BULK_LEN as u8, 0, 0,
];

/// String 0: the languages (US English only).
pub static LANGIDS: [u8; 4] = [4, 3, 0x09, 0x04];
/// String 1 and 2: manufacturer and product.
pub static MANUFACTURER: [u8; 16] = string(b"ddastep");
pub static PRODUCT: [u8; 26] = string(b"ddastep Grbl");

/// A string descriptor (Table 9-16) of ASCII text: UTF-16LE after the 2-byte header.
const fn string<const N: usize>(text: &[u8]) -> [u8; N] {
    assert!(N == 2 + 2 * text.len() && N < 256);
    let mut d = [0u8; N];
    d[0] = N as u8;
    d[1] = 3;
    let mut i = 0;
    while i < text.len() {
        d[2 + 2 * i] = text[i];
        i += 1;
    }
    d
}
