// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the state fields of a gamepad (the real class also parses them from the Driver Station). */
public class Gamepad {
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

    public Gamepad() {
    }
}
