// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.util;

public class Range {
    public static double scale(double n, double x1, double x2, double y1, double y2) {
        return y1 + (n - x1) * (y2 - y1) / (x2 - x1);
    }

    public static double clip(double number, double min, double max) {
        return number < min ? min : (number > max ? max : number);
    }

    public static float clip(float number, float min, float max) {
        return number < min ? min : (number > max ? max : number);
    }

    public static int clip(int number, int min, int max) {
        return number < min ? min : (number > max ? max : number);
    }
}
