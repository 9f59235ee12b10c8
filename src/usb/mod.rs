//! The USB device side of the CDC ACM port, free of HAL types: the descriptors as static
//! bytes, endpoint 0's control requests (chapter 9 and CDC ACM) and the bulk IN packet rule.
//!
//! Who uses it: the firmware's USB glue (`src/firmware/usb.rs`, which moves packets between
//! these and stm32-usbd's register driver) and the host tests `tests/usb_control.rs` and
//! `tests/usb_bulk_in.rs`. The bulk OUT side (realtime bytes, flow control) is
//! [`crate::grbl::packet`].
//!
//! Why not usb-device's `UsbDevice` and usbd-serial's `CdcAcmClass` (the well-kept crates):
//! flash, the binding constraint. With them the USB port cost 8 216 B (USB_LP_CAN_RX0 with
//! usb-device's poll and control pipe inlined 3 616, usb-device's other functions 2 106,
//! usbd-serial 784, our glue 764, stm32-usbd 172, the rest core's panics and slices) and the
//! image was 67 570 B, 4 082 B over the 62 KiB budget. Keeping `UsbDevice` with a class of our
//! own could have saved at most usbd-serial's 784 B. One device with one configuration and fixed
//! descriptors needs a small part of their generality (a class list walked per request,
//! descriptor writers run per GET_DESCRIPTOR, an endpoint allocator, string tables): the port
//! now costs 3 944 B (image 63 298 B, 59 354 B without it). stm32-usbd still drives the
//! registers and the packet memory, through usb-device's `bus::UsbBus` trait.

pub mod bulk_in;
pub mod control;
pub mod descriptors;
