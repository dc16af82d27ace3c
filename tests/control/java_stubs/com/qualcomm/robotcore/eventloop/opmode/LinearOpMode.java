// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.qualcomm.robotcore.eventloop.opmode;
import com.qualcomm.robotcore.hardware.HardwareMap;
public abstract class LinearOpMode {
    public HardwareMap hardwareMap;
    public abstract void runOpMode() throws InterruptedException;
    public final boolean opModeIsActive() { return false; }
}
