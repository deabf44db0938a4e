#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(
    init: caveray_fuzz::harness::codec_panics_are_errors(),
    |data: &[u8]| caveray_fuzz::harness::dicom(data)
);
