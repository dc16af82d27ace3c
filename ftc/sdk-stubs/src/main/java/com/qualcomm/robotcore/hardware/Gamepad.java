// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/**
 * Stub: the state fields of a gamepad (the real class also parses them from the Driver Station), and the
 * rumble and edge-detection methods used by official samples (here they do nothing / report false).
 */
public class Gamepad {
    /** Duration for rumble(...) meaning "until told otherwise". */
    public static final int RUMBLE_DURATION_CONTINUOUS = -1;

    public volatile float left_stick_x = 0f;
    public volatile float left_stick_y = 0f;
    public volatile float right_stick_x = 0f;
    public volatile float right_stick_y = 0f;
    public volatile boolean dpad_up = false;
    public volatile boolean dpad_down = false;
    public volatile boolean dpad_left = false;
    public volatile boolean dpad_right = false;
    public volatile boolean a = false;
    public volatile boolean b = false;
    public volatile boolean x = false;
    public volatile boolean y = false;
    public volatile boolean guide = false;
    public volatile boolean start = false;
    public volatile boolean back = false;
    public volatile boolean left_bumper = false;
    public volatile boolean right_bumper = false;
    public volatile boolean left_stick_button = false;
    public volatile boolean right_stick_button = false;
    public volatile float left_trigger = 0f;
    public volatile float right_trigger = 0f;
    public volatile boolean left_trigger_pressed = false;
    public volatile boolean right_trigger_pressed = false;
    public volatile boolean touchpad_finger_1 = false;
    public volatile boolean touchpad_finger_2 = false;
    public volatile float touchpad_finger_1_x = 0f;
    public volatile float touchpad_finger_1_y = 0f;
    public volatile float touchpad_finger_2_x = 0f;
    public volatile float touchpad_finger_2_y = 0f;

    public Gamepad() {
    }

    /** Stub: a sequence of rumble steps, made with a Builder. */
    public static class RumbleEffect {
        private RumbleEffect() {
        }

        /** Stub: collects (left power, right power, duration) steps. */
        public static class Builder {
            public Builder() {
            }

            /** Adds a step: rumble motor powers in [0, 1] for durationMs. */
            public Builder addStep(double rumble1, double rumble2, int durationMs) {
                return this;
            }

            public RumbleEffect build() {
                return new RumbleEffect();
            }
        }
    }

    /** Stub: does nothing (no Driver Station). */
    public void runRumbleEffect(RumbleEffect effect) {
    }

    /** Stub: does nothing (no Driver Station). */
    public void rumble(double rumble1, double rumble2, int durationMs) {
    }

    /** Stub: does nothing (no Driver Station). */
    public void stopRumble() {
    }

    /** Stub: does nothing (no Driver Station). */
    public void rumbleBlips(int count) {
    }

    /** Stub: never rumbling. */
    public boolean isRumbling() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean leftBumperWasPressed() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean leftBumperWasReleased() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean rightBumperWasPressed() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean rightBumperWasReleased() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean leftTriggerWasPressed() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean leftTriggerWasReleased() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean rightTriggerWasPressed() {
        return false;
    }

    /** Stub: no edges are tracked, always false. */
    public boolean rightTriggerWasReleased() {
        return false;
    }
}
