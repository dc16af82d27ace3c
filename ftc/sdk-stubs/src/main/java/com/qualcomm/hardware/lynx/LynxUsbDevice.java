// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.hardware.lynx;

import com.qualcomm.robotcore.hardware.HardwareDevice;

/** Stub: only the type (the first argument of the LynxModule constructor). */
public interface LynxUsbDevice extends HardwareDevice {
}
