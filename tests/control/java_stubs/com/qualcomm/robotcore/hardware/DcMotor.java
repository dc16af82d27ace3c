// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.qualcomm.robotcore.hardware;
public interface DcMotor extends HardwareDevice {
    enum RunMode { RUN_WITHOUT_ENCODER, RUN_USING_ENCODER, RUN_TO_POSITION, STOP_AND_RESET_ENCODER }
    void setMode(RunMode mode);
    void setPower(double power);
    int getCurrentPosition();
}
