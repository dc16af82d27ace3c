/* motorlab JVM test: the motor port, the relay's digital channel and the battery sensor of the simulated hub. */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.qualcomm.robotcore.hardware.DcMotor;
import com.qualcomm.robotcore.hardware.DcMotorEx;
import com.qualcomm.robotcore.hardware.DigitalChannel;
import com.qualcomm.robotcore.hardware.VoltageSensor;
import org.firstinspires.ftc.robotcore.external.navigation.CurrentUnit;

/** Simulated devices; each call costs the hub's command time, reads come from the bulk cache. */
public final class SimDevices {
    private SimDevices() {
    }

    /** A motor port: encoder from the bulk data, power to the plant's H-bridge. */
    public static final class Motor implements DcMotorEx {
        private final SimHub hub;
        private Direction direction = Direction.FORWARD;
        private ZeroPowerBehavior zeroPower = ZeroPowerBehavior.BRAKE;
        private RunMode mode = RunMode.RUN_WITHOUT_ENCODER;
        private double power;
        private int offset;
        private int target;

        public Motor(SimHub hub) {
            this.hub = hub;
        }

        private int sign() {
            return direction == Direction.FORWARD ? 1 : -1;
        }

        @Override
        public void setPower(double power) {
            hub.command();
            this.power = power;
            hub.plant.hubPower = sign() * power;
            hub.plant.brake = power == 0.0 && zeroPower == ZeroPowerBehavior.BRAKE;
        }

        @Override
        public double getPower() {
            return power;
        }

        @Override
        public int getCurrentPosition() {
            return sign() * (hub.counts() - offset);
        }

        @Override
        public double getVelocity() {
            return sign() * hub.velocity();
        }

        @Override
        public double getCurrent(CurrentUnit unit) {
            hub.command();
            double milliamps = Math.rint(Math.abs(hub.plant.current()) * 1000.0);
            return unit.convert(milliamps, CurrentUnit.MILLIAMPS);
        }

        @Override
        public void setMode(RunMode mode) {
            hub.command();
            if (mode == RunMode.STOP_AND_RESET_ENCODER) {
                offset = hub.counts();
                hub.clearBulkCache();
                setPower(0.0);
            }
            this.mode = mode;
        }

        @Override
        public RunMode getMode() {
            return mode;
        }

        @Override
        public void setZeroPowerBehavior(ZeroPowerBehavior zeroPowerBehavior) {
            hub.command();
            zeroPower = zeroPowerBehavior;
            hub.plant.brake = power == 0.0 && zeroPower == ZeroPowerBehavior.BRAKE;
        }

        @Override
        public ZeroPowerBehavior getZeroPowerBehavior() {
            return zeroPower;
        }

        @Override
        public void setDirection(Direction direction) {
            this.direction = direction;
        }

        @Override
        public Direction getDirection() {
            return direction;
        }

        @Override
        public int getPortNumber() {
            return 0;
        }

        @Override
        public void setTargetPosition(int position) {
            target = position;
        }

        @Override
        public int getTargetPosition() {
            return target;
        }

        @Override
        public boolean isBusy() {
            return false;
        }

        @Override
        public Manufacturer getManufacturer() {
            return Manufacturer.Other;
        }

        @Override
        public String getDeviceName() {
            return "simulated motor";
        }

        @Override
        public String getConnectionInfo() {
            return "simulated hub port 0";
        }

        @Override
        public int getVersion() {
            return 1;
        }

        @Override
        public void resetDeviceConfigurationForOpMode() {
        }

        @Override
        public void close() {
        }
    }

    /** A digital output driving the relay (high = closed). */
    public static final class Relay implements DigitalChannel {
        private final SimHub hub;
        private Mode mode = Mode.INPUT;
        private boolean state;

        public Relay(SimHub hub) {
            this.hub = hub;
        }

        @Override
        public Mode getMode() {
            return mode;
        }

        @Override
        public void setMode(Mode mode) {
            hub.command();
            this.mode = mode;
        }

        @Override
        public boolean getState() {
            return state;
        }

        @Override
        public void setState(boolean state) {
            hub.command();
            this.state = state;
            hub.plant.relayClosed = mode == Mode.OUTPUT && state;
        }

        @Override
        public Manufacturer getManufacturer() {
            return Manufacturer.Other;
        }

        @Override
        public String getDeviceName() {
            return "simulated relay";
        }

        @Override
        public String getConnectionInfo() {
            return "simulated digital 0";
        }

        @Override
        public int getVersion() {
            return 1;
        }

        @Override
        public void resetDeviceConfigurationForOpMode() {
        }

        @Override
        public void close() {
        }
    }

    /** The hub's input voltage, to 1 mV. */
    public static final class Battery implements VoltageSensor {
        private final SimHub hub;

        public Battery(SimHub hub) {
            this.hub = hub;
        }

        @Override
        public double getVoltage() {
            hub.command();
            return Math.rint(hub.plant.battery() * 1000.0) / 1000.0;
        }

        @Override
        public Manufacturer getManufacturer() {
            return Manufacturer.Lynx;
        }

        @Override
        public String getDeviceName() {
            return "simulated battery";
        }

        @Override
        public String getConnectionInfo() {
            return "simulated hub";
        }

        @Override
        public int getVersion() {
            return 1;
        }

        @Override
        public void resetDeviceConfigurationForOpMode() {
        }

        @Override
        public void close() {
        }
    }
}
