//! The parameter list of the DMA-22(A) module (manual 000, chapter 7,
//! table 5), one CoE entry per parameter: ID n < 0xFF is subindex n + 1 of
//! the module's object 0x80n0, ID n >= 0xFF subindex n - 0xFE of 0x80n1.
//! Generated once from the table by hand-checked rules; every deviation
//! from the printed row is in `NOTES.md` ("Parameter list").

use ecat_slave::od::DataType::{Int16, UInt16};
use ecat_slave::od::build::sub0;
use ecat_slave::od::{Entry, Limits};

use super::map::{ro, rw};

/// Parameters with IDs 0x00..=0xFE (object 0x80n0): 169 entries.
#[rustfmt::skip]
pub const PARAMETERS_LOW: &[Entry] = &[
    sub0(255),
    ro(1, "Vers Software version", UInt16, 1001, &Limits::range(0, 65535, "")), // ID 0x00
    ro(2, "d1.01 Sum of analogue set value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x01
    ro(3, "d1.02 Sum of all post ramp set values", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x02
    ro(4, "d1.03 Set values after linearization", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x03
    ro(5, "d1.04 Value after gain adjustment", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x04
    ro(6, "d1.05 Signal A", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x05
    ro(7, "d1.06 Signal B", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x06
    ro(8, "d1.07 Current A", UInt16, 0, &Limits::range(0, 5000, "mA")), // ID 0x07
    ro(9, "d1.08 Current B", UInt16, 0, &Limits::range(0, 5000, "mA")), // ID 0x08
    ro(10, "d1.09 Total current", UInt16, 0, &Limits::range(0, 5000, "mA")), // ID 0x09
    ro(11, "d1.10 Desired value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0A
    ro(12, "d1.11 Actual value, feedback value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0B
    ro(13, "d1.12 Lag error", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0C
    ro(14, "d1.13 Controller output", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0D
    ro(15, "d2.01 Sum of analogue set value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0E
    ro(16, "d2.02 Sum of all post ramp set values", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x0F
    ro(17, "d2.03 Set values after linearization", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x10
    ro(18, "d2.04 Value after gain adjustment", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x11
    ro(19, "d2.10 Desired value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x12
    ro(20, "d2.11 Actual value, feedback value", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x13
    ro(21, "d2.12 Lag error", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x14
    ro(22, "d2.13 Controller output", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x15
    rw(23, "S1.01 Set Value1", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x16
    rw(24, "S1.02 Set Value2", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x17
    rw(25, "S1.03 Set Value3", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x18
    rw(26, "S1.04 Set Value4", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x19
    rw(28, "r1.01 Ramp from 0 -> -", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x1B
    rw(29, "r1.02 Ramp from - -> 0", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x1C
    rw(30, "r1.03 Ramp from 0 -> +", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x1D
    rw(31, "r1.04 Ramp from + -> 0", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x1E
    rw(32, "A1.01 Ethernet set value (Branch 1)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x1F
    rw(33, "A1.02 Ethernet feedback value (Branch 1)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x20
    rw(34, "S2.01 Set Value1 (Branch 2)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x21
    rw(35, "S2.02 Set Value2 (Branch 2)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x22
    rw(36, "r2.01 Ramp from 0 -> -", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x23
    rw(37, "r2.02 Ramp from - -> 0", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x24
    rw(38, "r2.03 Ramp from 0 -> + (Branch 2)", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x25
    rw(39, "r2.04 Ramp from + -> 0 (Branch 2)", UInt16, 0, &Limits::range(0, 3950, "")), // ID 0x26
    rw(40, "A2.01 Ethernet set value (Branch 2)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x27
    rw(41, "A2.02 Ethernet feedback value (Branch 2)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x28
    rw(42, "C1.00 Controller selection", UInt16, 1, &Limits::range(0, 4, "")), // ID 0x29
    rw(43, "C1.01 Safety function", UInt16, 0, &Limits::range(0, 1, "")), // ID 0x2A
    rw(44, "C1.02 Linearization", UInt16, 0, &Limits::range(0, 6, "")), // ID 0x2B
    rw(45, "C1.03 Gain A", UInt16, 100, &Limits::range(0, 200, "")), // ID 0x2C
    rw(46, "C1.04 Gain B", UInt16, 100, &Limits::range(0, 200, "")), // ID 0x2D
    rw(47, "C1.05 Set value sign and gain", Int16, 100, &Limits::range(-400, 400, "")), // ID 0x2E
    rw(48, "C1.06 Set value offset", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x2F
    rw(49, "C1.07 Dead band compensation A", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x30
    rw(50, "C1.08 Dead band compensation B", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x31
    rw(51, "C1.09 Sensor type", UInt16, 4, &Limits::range(1, 28, "")), // ID 0x32
    rw(52, "C1.10 Actual value gain", UInt16, 100, &Limits::range(0, 400, "")), // ID 0x33
    rw(53, "C1.11 Actual value offset", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x34
    rw(54, "C1.12 Actual value sign", Int16, 1, &Limits::range(-1, 1, "")), // ID 0x35
    rw(55, "C1.13 P-Portion K P1", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x36
    rw(56, "C1.14 T-Portion for PT1 (to C1.16)", UInt16, 0, &Limits::range(0, 1000, "")), // ID 0x37
    rw(57, "C1.15 Threshold (C1.13, C1.16)", UInt16, 9999, &Limits::range(0, 9999, "mV")), // ID 0x38
    rw(58, "C1.16 P-Portion K P2", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x39
    rw(59, "C1.17 I-Portion", UInt16, 0, &Limits::range(0, 4000, "")), // ID 0x3A
    rw(60, "C1.18 D-Portion", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x3B
    rw(61, "C1.19 T-Portion for DT1", UInt16, 0, &Limits::range(0, 1000, "")), // ID 0x3C
    rw(62, "C1.20 Gain ( C1.13 and C1.16)", UInt16, 1, &Limits::range(1, 32, "")), // ID 0x3D
    rw(63, "C1.21 Comparator upper level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x3E
    rw(64, "C1.22 Comparator lower level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x3F
    rw(65, "C1.23 Comparator delay into window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0x40
    rw(66, "C1.24 Comparator delay out of window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0x41
    rw(67, "C1.25 Comparator selection COMP_1", UInt16, 0, &Limits::range(0, 3, "")), // ID 0x42
    rw(68, "C1.26 Cable fracture detection feedback", UInt16, 0, &Limits::range(0, 1, "")), // ID 0x43
    rw(69, "C2.00 Controller selection", UInt16, 0, &Limits::range(0, 4, "")), // ID 0x44
    rw(70, "C2.01 Safety function", UInt16, 0, &Limits::range(0, 1, "")), // ID 0x45
    rw(71, "C2.02 Linearization", UInt16, 0, &Limits::range(0, 6, "")), // ID 0x46
    rw(72, "C2.03 Gain A", UInt16, 100, &Limits::range(0, 200, "")), // ID 0x47
    rw(73, "C2.04 Gain B", UInt16, 100, &Limits::range(0, 200, "")), // ID 0x48
    rw(74, "C2.05 Set value sign and gain", Int16, 100, &Limits::range(-400, 400, "")), // ID 0x49
    rw(75, "C2.06 Set value offset", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x4A
    rw(76, "C2.07 Dead band compensation A", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x4B
    rw(77, "C2.08 Dead band compensation B", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x4C
    rw(78, "C2.09 Sensor type", UInt16, 4, &Limits::range(0, 12, "")), // ID 0x4D
    rw(79, "C2.10 Actual value gain", UInt16, 100, &Limits::range(0, 400, "")), // ID 0x4E
    rw(80, "C2.11 Actual value offset", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x4F
    rw(81, "C2.12 Actual value sign", Int16, 1, &Limits::range(-1, 1, "")), // ID 0x50
    rw(82, "C2.13 P-Portion K P1", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x51
    rw(83, "C2.14 T-Portion for PT1 (to C1.16)", UInt16, 0, &Limits::range(0, 1000, "")), // ID 0x52
    rw(84, "C2.15 Threshold (C1.13, C1.16)", UInt16, 9999, &Limits::range(0, 9999, "mV")), // ID 0x53
    rw(85, "C2.16 P-Portion K P2", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x54
    rw(86, "C2.17 I-Portion", UInt16, 0, &Limits::range(0, 4000, "")), // ID 0x55
    rw(87, "C2.18 D-Portion", UInt16, 0, &Limits::range(0, 400, "")), // ID 0x56
    rw(88, "C2.19 T-Portion for DT1", UInt16, 0, &Limits::range(0, 1000, "")), // ID 0x57
    rw(89, "C2.20 Gain (C1.13 and C1.16)", UInt16, 1, &Limits::range(1, 32, "")), // ID 0x58
    rw(90, "C2.21 Comparator upper level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x59
    rw(91, "C2.22 Comparator lower level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0x5A
    rw(92, "C2.23 Comparator delay into window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0x5B
    rw(93, "C2.24 Comparator delay out of window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0x5C
    rw(94, "C2.25 Comparator selection COMP_2", UInt16, 0, &Limits::range(0, 3, "")), // ID 0x5D
    rw(95, "C2.26 Cable fracture detection feedback", UInt16, 0, &Limits::range(0, 1, "")), // ID 0x5E
    ro(96, "E00 Operation mode (depends on HW + SW version)", UInt16, 3, &Limits::range(1, 11, "")), // ID 0x5F
    rw(97, "E01 Analogue output (depends on HW + SW version)", UInt16, 1, &Limits::range(1, 21, "")), // ID 0x60
    rw(98, "E02 Push-Pull function (depends on HW + SW version)", UInt16, 0, &Limits::range(0, 1, "")), // ID 0x61
    rw(99, "E03 Solenoid selection Solenoid selection A (depends on HW + SW version)", UInt16, 6, &Limits::range(1, 7, "")), // ID 0x62
    ro(100, "E04 P-Portion current contr. Energization A", UInt16, 500, &Limits::range(500, 9999, "")), // ID 0x63
    ro(101, "E05 I-Portion current contr. Energization A", UInt16, 500, &Limits::range(500, 9999, "")), // ID 0x64
    ro(102, "E06 P-Portion cur. contr. de-energization A", UInt16, 1300, &Limits::range(1300, 9999, "")), // ID 0x65
    ro(103, "E07 I-Portion cur. contr. De-energization A", UInt16, 500, &Limits::range(500, 9999, "")), // ID 0x66
    rw(104, "E08 Ramp selection", UInt16, 1, &Limits::range(1, 2, "")), // ID 0x67
    rw(105, "E09 Time delay enable signal", UInt16, 0, &Limits::range(0, 9999, "ms")), // ID 0x68
    rw(106, "E10 Solenoid current adaptation A", UInt16, 100, &Limits::range(50, 110, "")), // ID 0x69
    rw(107, "E11 Initial current solenoid A", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x6A
    rw(108, "E12 Initial current solenoid B", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0x6B
    rw(109, "E13 Dither Amplitude A", UInt16, 0, &Limits::range(0, 3000, "mV")), // ID 0x6C
    rw(110, "E14 Dither Frequency A", UInt16, 0, &Limits::range(0, 300, "")), // ID 0x6D
    rw(111, "E15 Selection set point S1.06 (U/I)", UInt16, 1, &Limits::range(0, 11, "")), // ID 0x6E
    rw(113, "E17 Set value activation mode", UInt16, 0, &Limits::range(0, 2, "")), // ID 0x70
    rw(114, "E18 Error/Comparator Output", UInt16, 0, &Limits::range(0, 8, "")), // ID 0x71
    rw(115, "E19 Factor for analog output (depends on HW + SW version)", Int16, 100, &Limits::range(-400, 400, "")), // ID 0x72
    rw(164, "E22 Ethernet Slave Address", UInt16, 0, &Limits::range(0, 32, "")), // ID 0xA3
    rw(165, "C1.27 Hysteresis command A", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xA4
    rw(166, "C2.27 Hysteresis command B", Int16, 0, &Limits::range(-9999, 9999, "")), // ID 0xA5
    rw(167, "C1.28 Comparator upper level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xA6
    rw(168, "C1.29 Comparator lower level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xA7
    rw(169, "C1.30 Comparator delay into window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0xA8
    rw(170, "C1.31 Comparator delay out of window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0xA9
    rw(171, "C1.32 Comparator selection Comp_11", UInt16, 0, &Limits::range(0, 3, "")), // ID 0xAA
    rw(172, "C2.28 Comparator upper level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xAB
    rw(173, "C2.29 Comparator lower level", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xAC
    rw(174, "C2.30 Comparator delay into window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0xAD
    rw(175, "C2.31 Comparator delay out of window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0xAE
    rw(176, "C2.32 Comparator selection Comp_22", UInt16, 0, &Limits::range(0, 3, "")), // ID 0xAF
    rw(177, "EInt Internal Digital Switches (Read/Set)", UInt16, 0, &Limits::range(0, 65535, "")), // ID 0xB0
    rw(178, "E23 Ethernet telegram timeout window", UInt16, 0, &Limits::range(0, 9999, "")), // ID 0xB1
    rw(180, "C1.33 I-portion limitation", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xB3
    rw(181, "C2.33 I-portion limitation", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xB4
    rw(204, "E24 Ethernet DHCP function", UInt16, 1, &Limits::range(0, 1, "")), // ID 0xCB
    rw(205, "E25 Ethernet-IP byte aaa", UInt16, 0, &Limits::range(0, 255, "")), // ID 0xCC
    rw(206, "E26 Ethernet-IP byte bbb / timeout acknowledge", UInt16, 0, &Limits::range(0, 255, "")), // ID 0xCD
    rw(207, "E27 Ethernet-IP byte ccc", UInt16, 0, &Limits::range(0, 255, "")), // ID 0xCE
    ro(208, "E28 Ethernet-IP byte ddd", UInt16, 0, &Limits::range(0, 255, "")), // ID 0xCF
    rw(209, "E29 Ethernet input buffer length", UInt16, 0, &Limits::range(0, 32, "")), // ID 0xD0
    rw(210, "E30 Ethernet Output buffer length", UInt16, 0, &Limits::range(0, 32, "")), // ID 0xD1
    rw(213, "E33 Offset for analog output (depends on HW + SW version)", Int16, 0, &Limits::range(-9999, 9999, "mV")), // ID 0xD4
    rw(219, "C1.36 Sensor signal correction factor for signal < 0. branch 1", Int16, 100, &Limits::range(-100, 100, "")), // ID 0xDA
    rw(220, "C2.36 Sensor signal correction factor for signal < 0. branch 2", Int16, 100, &Limits::range(-100, 100, "")), // ID 0xDB
    rw(221, "C1.37 Spool overlap compensation A", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xDC
    rw(222, "C1.38 Spool overlap compensation B", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xDD
    rw(223, "C2.37 Spool overlap compensation A", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xDE
    rw(224, "C2.38 Spool overlap compensation B", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xDF
    rw(231, "L1.x0 Linearization curve branch 1 [0,0]", UInt16, 0, &Limits::range(0, 0, "mV")), // ID 0xE6
    rw(232, "L1.y0 Linearization curve [0,0]", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xE7
    rw(233, "L1.x1 Linearization curve [1,1]", UInt16, 1250, &Limits::range(0, 9999, "mV")), // ID 0xE8
    rw(234, "L1.y1 Linearization curve [1,1]", UInt16, 1250, &Limits::range(0, 9999, "mV")), // ID 0xE9
    rw(235, "L1.x2 Linearization curve [2,2]", UInt16, 2500, &Limits::range(0, 9999, "mV")), // ID 0xEA
    rw(236, "L1.y2 Linearization curve [2,2]", UInt16, 2500, &Limits::range(0, 9999, "mV")), // ID 0xEB
    rw(237, "L1.x3 Linearization curve [3,3]", UInt16, 3750, &Limits::range(0, 9999, "mV")), // ID 0xEC
    rw(238, "L1.y3 Linearization curve [3,3]", UInt16, 3750, &Limits::range(0, 9999, "mV")), // ID 0xED
    rw(239, "L1.x4 Linearization curve [4,4]", UInt16, 5000, &Limits::range(0, 9999, "mV")), // ID 0xEE
    rw(240, "L1.y4 Linearization curve [4,4]", UInt16, 5000, &Limits::range(0, 9999, "mV")), // ID 0xEF
    rw(241, "L1.x5 Linearization curve [5,5]", UInt16, 6250, &Limits::range(0, 9999, "mV")), // ID 0xF0
    rw(242, "L1.y5 Linearization curve [5,5]", UInt16, 6250, &Limits::range(0, 9999, "mV")), // ID 0xF1
    rw(243, "L1.x6 Linearization curve [6,6]", UInt16, 7500, &Limits::range(0, 9999, "mV")), // ID 0xF2
    rw(244, "L1.y6 Linearization curve [6,6]", UInt16, 7500, &Limits::range(0, 9999, "mV")), // ID 0xF3
    rw(245, "L1.x7 Linearization curve [7,7]", UInt16, 8750, &Limits::range(0, 9999, "mV")), // ID 0xF4
    rw(246, "L1.y7 Linearization curve [7,7]", UInt16, 8750, &Limits::range(0, 9999, "mV")), // ID 0xF5
    rw(247, "L1.x8 Linearization curve [8,8]", UInt16, 9999, &Limits::range(0, 9999, "mV")), // ID 0xF6
    rw(248, "L1.y8 Linearization curve [8,8]", UInt16, 9999, &Limits::range(9999, 9999, "mV")), // ID 0xF7
    rw(249, "L2.x0 Linearization curve branch 2 [0,0]", UInt16, 0, &Limits::range(0, 0, "mV")), // ID 0xF8
    rw(250, "L2.y0 Linearization curve [0,0]", UInt16, 0, &Limits::range(0, 9999, "mV")), // ID 0xF9
    rw(251, "L2.x1 Linearization curve [1,1]", UInt16, 1250, &Limits::range(0, 9999, "mV")), // ID 0xFA
    rw(252, "L2.y1 Linearization curve [1,1]", UInt16, 1250, &Limits::range(0, 9999, "mV")), // ID 0xFB
    rw(253, "L2.x2 Linearization curve [2,2]", UInt16, 2500, &Limits::range(0, 9999, "mV")), // ID 0xFC
    rw(254, "L2.y2 Linearization curve [2,2]", UInt16, 2500, &Limits::range(0, 9999, "mV")), // ID 0xFD
    rw(255, "L2.x3 Linearization curve [3,3]", UInt16, 3750, &Limits::range(0, 9999, "mV")), // ID 0xFE
];

/// Parameters with IDs 0xFF..=0x109 (object 0x80n1): 11 entries.
#[rustfmt::skip]
pub const PARAMETERS_HIGH: &[Entry] = &[
    sub0(11),
    rw(1, "L2.y3 Linearization curve [3,3]", UInt16, 3750, &Limits::range(0, 9999, "mV")), // ID 0xFF
    rw(2, "L2.x4 Linearization curve [4,4]", UInt16, 5000, &Limits::range(0, 9999, "mV")), // ID 0x100
    rw(3, "L2.y4 Linearization curve [4,4]", UInt16, 5000, &Limits::range(0, 9999, "mV")), // ID 0x101
    rw(4, "L2.x5 Linearization curve [5,5]", UInt16, 6250, &Limits::range(0, 9999, "mV")), // ID 0x102
    rw(5, "L2.y5 Linearization curve [5,5]", UInt16, 6250, &Limits::range(0, 9999, "mV")), // ID 0x103
    rw(6, "L2.x6 Linearization curve [6,6]", UInt16, 7500, &Limits::range(0, 9999, "mV")), // ID 0x104
    rw(7, "L2.y6 Linearization curve [6,6]", UInt16, 7500, &Limits::range(0, 9999, "mV")), // ID 0x105
    rw(8, "L2.x7 Linearization curve [7,7]", UInt16, 8750, &Limits::range(0, 9999, "mV")), // ID 0x106
    rw(9, "L2.y7 Linearization curve [7,7]", UInt16, 8750, &Limits::range(0, 9999, "mV")), // ID 0x107
    rw(10, "L2.x8 Linearization curve [8,8]", UInt16, 9999, &Limits::range(0, 9999, "mV")), // ID 0x108
    rw(11, "L2.y8 Linearization curve [8,8]", UInt16, 9999, &Limits::range(9999, 9999, "mV")), // ID 0x109
];
