// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the register read/write subset of I2cDeviceSynchSimple (no time stamps, logging, health). */
public interface I2cDeviceSynchSimple extends HardwareDevice, I2cAddrConfig {
    byte read8(int ireg);

    byte[] read(int ireg, int creg);

    void write8(int ireg, int bVal);

    void write(int ireg, byte[] data);

    void write8(int ireg, int bVal, I2cWaitControl waitControl);

    void write(int ireg, byte[] data, I2cWaitControl waitControl);

    void waitForWriteCompletions(I2cWaitControl waitControl);

    void enableWriteCoalescing(boolean enable);

    boolean isWriteCoalescingEnabled();

    boolean isArmed();
}
