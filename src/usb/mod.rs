//! The USB device side of the CDC ACM port, free of HAL types: the descriptors as static
//! bytes, endpoint 0's control requests (chapter 9 and CDC ACM) and the bulk IN packet rule.
//!
//! Who uses it: the firmware's USB glue (`src/firmware/usb.rs`, which moves packets between
//! these and stm32-usbd's register driver) and the host tests `tests/usb_control.rs` and
//! `tests/usb_bulk_in.rs`. The bulk OUT side (realtime bytes, flow control) is
//! [`crate::grbl::packet`].
//!
//! Why not usb-device's `UsbDevice` and usbd-serial's `CdcAcmClass`: flash. With them the
//! `usb` image was 67 570 B (USB: 8 216 B), 4 082 B over the 62 KiB budget; one device with one
//! configuration and fixed descriptors needs a small part of their generality (a class list
//! walked per request, descriptor writers run per GET_DESCRIPTOR, an endpoint allocator).
//! stm32-usbd still drives the registers and the packet memory, through usb-device's
//! `bus::UsbBus` trait.

pub mod bulk_in;
pub mod control;
pub mod descriptors;
