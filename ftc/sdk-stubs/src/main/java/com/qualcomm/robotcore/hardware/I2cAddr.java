// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** An I2C address; the SDK keeps the 7-bit form. */
public final class I2cAddr {
    private final int address7Bit;

    public I2cAddr(int i2cAddr7Bit) {
        address7Bit = i2cAddr7Bit & 0x7F;
    }

    public static I2cAddr zero() {
        return new I2cAddr(0);
    }

    public static I2cAddr create7bit(int i2cAddr7Bit) {
        return new I2cAddr(i2cAddr7Bit);
    }

    public static I2cAddr create8bit(int i2cAddr8Bit) {
        return new I2cAddr(i2cAddr8Bit >> 1);
    }

    public int get7Bit() {
        return address7Bit;
    }

    public int get8Bit() {
        return address7Bit << 1;
    }
}
