// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.eventloop.opmode;

import com.qualcomm.robotcore.hardware.Gamepad;
import com.qualcomm.robotcore.hardware.HardwareMap;
import java.util.HashMap;
import org.firstinspires.ftc.robotcore.external.Telemetry;

/**
 * Stub of the iterative OpMode. The real SDK declares gamepad1/gamepad2/telemetry/hardwareMap in the
 * package-private superclass OpModeInternal; they are public fields either way. Here nothing runs
 * the init/loop cycle: a test harness sets the fields and calls the methods.
 */
public abstract class OpMode {
    /** Values kept across OpModes (e.g. from autonomous to TeleOp); static, as in the SDK. */
    public static final HashMap<String, Object> blackboard = new HashMap<String, Object>();

    public volatile Gamepad gamepad1 = new Gamepad();
    public volatile Gamepad gamepad2 = new Gamepad();
    public Telemetry telemetry = null;
    public volatile HardwareMap hardwareMap = null;
    public volatile double time = 0.0;

    volatile boolean stopRequested = false;
    private long startNanos = System.nanoTime();

    public OpMode() {
    }

    public abstract void init();

    public void init_loop() {
    }

    public void start() {
    }

    public abstract void loop();

    public void stop() {
    }

    /** As the SDK: ask the OpMode to stop (LinearOpMode.opModeIsActive() becomes false). */
    public final void requestOpModeStop() {
        stopRequested = true;
    }

    public final void terminateOpModeNow() {
        stopRequested = true;
    }

    public double getRuntime() {
        return (System.nanoTime() - startNanos) * 1e-9;
    }

    public void resetRuntime() {
        startNanos = System.nanoTime();
    }

    public void updateTelemetry(Telemetry telemetry) {
        telemetry.update();
    }
}
