// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.eventloop.opmode;

/**
 * Stub of LinearOpMode. There is no Driver Station: waitForStart() returns at once (as if START was
 * pressed), and the OpMode is active until requestOpModeStop() is called.
 */
public abstract class LinearOpMode extends OpMode {
    private volatile boolean started = false;

    public LinearOpMode() {
    }

    public abstract void runOpMode() throws InterruptedException;

    public void waitForStart() {
        started = true;
    }

    public final void idle() {
        Thread.yield();
    }

    public final void sleep(long milliseconds) {
        try {
            Thread.sleep(milliseconds);
        } catch (InterruptedException e) {
            Thread.currentThread().interrupt();
        }
    }

    public final boolean opModeIsActive() {
        return !isStopRequested() && isStarted();
    }

    public final boolean opModeInInit() {
        return !isStarted() && !isStopRequested();
    }

    public final boolean isStarted() {
        return started || Thread.currentThread().isInterrupted();
    }

    public final boolean isStopRequested() {
        return stopRequested || Thread.currentThread().isInterrupted();
    }

    @Override
    public final void init() {
    }

    @Override
    public final void init_loop() {
    }

    @Override
    public final void start() {
    }

    @Override
    public final void loop() {
    }

    @Override
    public final void stop() {
    }
}
